//! The LEAF section of a `.pvs` (format version 2, optional): for each stored cell, the
//! sorted numbers of the cells *it sees* in its source — for a BSP level, the visible
//! leaves (leaf numbers as in the BSP) next to the visible faces of the DATA section.
//! The sets are small (a leaf sees a few hundred leaves) and read whole at open, so
//! they are stored simply: each as its first number then the gaps between consecutive
//! numbers (postcard varints, mostly one byte), the whole table compressed with zstd.

use crate::error::PvsError;
use serde::{Deserialize, Serialize};

/// Gap-coded visible-leaf sets, one per stored cell in stored order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct LeafTable {
    /// Per stored cell: `[first, gap, gap, ...]`, every gap ≥ 1.
    pub sets: Vec<Vec<u32>>,
}

impl LeafTable {
    /// Gap-code `sets` (each sorted ascending without duplicates).
    pub fn of(sets: &[Vec<u32>]) -> Result<LeafTable, PvsError> {
        let sets = sets
            .iter()
            .enumerate()
            .map(|(k, s)| {
                if s.windows(2).any(|w| w[0] >= w[1]) {
                    return Err(PvsError::Invalid(format!(
                        "visible leaves of stored cell {k} are not sorted without duplicates"
                    )));
                }
                let mut prev = 0;
                Ok(s.iter()
                    .enumerate()
                    .map(|(i, &x)| {
                        let g = if i == 0 { x } else { x - prev };
                        prev = x;
                        g
                    })
                    .collect())
            })
            .collect::<Result<_, _>>()?;
        Ok(LeafTable { sets })
    }

    /// Decode every set, checking it against the stored cell count (untrusted input).
    pub fn decode(&self, stored: usize) -> Result<Vec<Vec<u32>>, PvsError> {
        let bad = |m: &str| PvsError::Corrupt(format!("visible leaves: {m}"));
        if self.sets.len() != stored {
            return Err(bad("one set per stored cell expected"));
        }
        self.sets
            .iter()
            .map(|gaps| {
                let mut out = Vec::with_capacity(gaps.len());
                let mut prev = 0u32;
                for (i, &g) in gaps.iter().enumerate() {
                    if i > 0 && g == 0 {
                        return Err(bad("a set is not strictly ascending"));
                    }
                    prev = if i == 0 {
                        g
                    } else {
                        prev.checked_add(g)
                            .ok_or_else(|| bad("a leaf number overflows"))?
                    };
                    out.push(prev);
                }
                Ok(out)
            })
            .collect()
    }
}

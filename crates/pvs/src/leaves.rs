//! The LEAF section of a `.pvs` (format version 2, optional): for each stored cell, the
//! sorted numbers of the cells *it sees* in its source — for a BSP level, the visible
//! leaves (leaf numbers as in the BSP) next to the visible faces of the DATA section.
//! The sets are small (a leaf sees a few hundred leaves) and read whole at open, so
//! they are stored simply: each as its first number then the gaps between consecutive
//! numbers (postcard varints, mostly one byte), the whole table compressed with zstd.

use crate::error::PvsError;
use sightline_runtime::wire::LeafTable;

/// Gap-code `sets` (each sorted ascending without duplicates).
pub(crate) fn leaf_table(sets: &[Vec<u32>]) -> Result<LeafTable, PvsError> {
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

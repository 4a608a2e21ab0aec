//! Distribution: `build --shard I/N` computes a deterministic 1/N of the cells, and
//! [`merge`] joins the shard files into a file byte-identical to a whole build.
//!
//! Shard `I` of `N` owns the cells whose index is `I mod N` (interleaved, so costly
//! districts are spread over the shards). A shard file is an ordinary `.pvs` whose header
//! says which shard it is and whose cell table lists every cell of the build but stores
//! the sets of its own cells only.

use crate::error::PvsError;
use crate::format::{encode_cells_with_leaves, EncodeOptions, Header};
use crate::query::PvsFile;
use roaring::RoaringBitmap;

/// Merge shard files (or complete files of the same build) into the bytes of a complete
/// `.pvs`. Every input must share the scene fingerprint, method, parameters and cells,
/// and together they must store every cell exactly once.
pub fn merge(inputs: &[(String, PvsFile)]) -> Result<Vec<u8>, PvsError> {
    let Some((first_name, first)) = inputs.first() else {
        return Err(PvsError::Merge("no input files".into()));
    };
    let h0 = first.header();
    let n = first.cells().len();
    let mut owner: Vec<Option<usize>> = vec![None; n];
    for (k, (name, f)) in inputs.iter().enumerate() {
        let h = f.header();
        let differ =
            |what: &str| PvsError::Merge(format!("{name} and {first_name} have different {what}"));
        if h.fingerprint != h0.fingerprint || h.object_count != h0.object_count {
            return Err(differ("scenes (fingerprints)"));
        }
        if h.method != h0.method {
            return Err(differ(&format!("methods ({} vs {})", h.method, h0.method)));
        }
        if h.params != h0.params {
            return Err(differ("method parameters"));
        }
        if f.cells() != first.cells() {
            return Err(differ("cells"));
        }
        for c in f.stored() {
            if let Some(o) = owner[c as usize].replace(k) {
                return Err(PvsError::Merge(format!(
                    "cell {c} is in both {} and {name}",
                    inputs[o].0
                )));
            }
        }
    }
    let missing: Vec<usize> = (0..n).filter(|&c| owner[c].is_none()).collect();
    if let Some(&m) = missing.first() {
        return Err(PvsError::Merge(format!(
            "{} cells are in no input (first: cell {m}); is a shard missing?",
            missing.len()
        )));
    }
    let sets: Vec<RoaringBitmap> = (0..n)
        .map(|c| inputs[owner[c].unwrap_or(0)].1.bitmap(c))
        .collect::<Result<_, _>>()?;
    // Visible leaves are carried when every input has them.
    let with_leaves = inputs
        .iter()
        .filter(|(_, f)| f.has_visible_leaves())
        .count();
    if with_leaves != 0 && with_leaves != inputs.len() {
        return Err(PvsError::Merge(
            "some inputs store visible leaves and others do not".into(),
        ));
    }
    let leaves: Option<Vec<Vec<u32>>> = (with_leaves > 0)
        .then(|| {
            (0..n)
                .map(|c| {
                    inputs[owner[c].unwrap_or(0)]
                        .1
                        .visible_leaves(c)
                        .map(<[u32]>::to_vec)
                        .ok_or_else(|| {
                            PvsError::Corrupt(format!("cell {c}: no visible leaves stored"))
                        })
                })
                .collect::<Result<_, _>>()
        })
        .transpose()?;
    let header = Header {
        shard: None,
        ..h0.clone()
    };
    let present: Vec<u32> = (0..n as u32).collect();
    encode_cells_with_leaves(
        &header,
        &first.shaped_cells(),
        &present,
        &sets,
        leaves.as_deref(),
        &EncodeOptions::default(),
    )
}

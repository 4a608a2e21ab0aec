//! Distribution: `build --shard I/N` computes a deterministic 1/N of the cells, and
//! [`merge`] joins the shard files into a file byte-identical to a whole build.
//!
//! Shard `I` of `N` owns the cells whose index is `I mod N` (interleaved, so costly
//! districts are spread over the shards). A shard file is an ordinary `.pvs` whose header
//! says which shard it is and whose cell table lists every cell of the build but stores
//! the sets of its own cells only.

use crate::format::{encode_bitmaps, Header};
use crate::query::PvsFile;
use crate::PvsError;
use roaring::RoaringBitmap;
use serde::{Deserialize, Serialize};

/// Shard `index` of `count` (0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

/// Environment variables that name the shard of `--shard auto/N`, in order of preference:
/// a Kubernetes Indexed Job and a Slurm job array.
pub const SHARD_ENV: [&str; 2] = ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"];

impl Shard {
    /// Parse `I/N`, or `auto/N` taking `I` from `env(JOB_COMPLETION_INDEX)` or
    /// `env(SLURM_ARRAY_TASK_ID)`.
    ///
    /// ```
    /// use sightline_pvs::Shard;
    /// assert_eq!(Shard::parse("2/8", |_| None).unwrap(), Shard { index: 2, count: 8 });
    /// let env = |k: &str| (k == "SLURM_ARRAY_TASK_ID").then(|| "3".to_string());
    /// assert_eq!(Shard::parse("auto/4", env).unwrap(), Shard { index: 3, count: 4 });
    /// assert!(Shard::parse("4/4", |_| None).is_err());
    /// ```
    pub fn parse(s: &str, env: impl Fn(&str) -> Option<String>) -> Result<Shard, PvsError> {
        let bad = |m: String| PvsError::Invalid(format!("--shard {s}: {m}"));
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| bad("expected I/N or auto/N".into()))?;
        let count: u32 = n
            .trim()
            .parse()
            .map_err(|_| bad(format!("'{n}' is not a shard count")))?;
        let index: u32 = if i.trim() == "auto" {
            let (var, v) = SHARD_ENV
                .iter()
                .find_map(|k| env(k).map(|v| (*k, v)))
                .ok_or_else(|| {
                    bad(format!(
                        "auto needs {} or {} in the environment",
                        SHARD_ENV[0], SHARD_ENV[1]
                    ))
                })?;
            v.trim()
                .parse()
                .map_err(|_| bad(format!("{var}='{v}' is not a shard index")))?
        } else {
            i.trim()
                .parse()
                .map_err(|_| bad(format!("'{i}' is not a shard index")))?
        };
        let shard = Shard { index, count };
        shard
            .validate()
            .map_err(|_| bad(format!("need 0 <= I < N, got {index}/{count}")))?;
        Ok(shard)
    }

    pub fn validate(&self) -> Result<(), PvsError> {
        if self.count == 0 || self.index >= self.count {
            return Err(PvsError::Corrupt(format!(
                "bad shard {}/{}",
                self.index, self.count
            )));
        }
        Ok(())
    }

    /// Whether cell `cell` belongs to this shard.
    pub fn owns(&self, cell: usize) -> bool {
        cell as u64 % self.count as u64 == self.index as u64
    }
}

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
    let header = Header {
        shard: None,
        ..h0.clone()
    };
    let present: Vec<u32> = (0..n as u32).collect();
    encode_bitmaps(&header, first.cells(), &present, &sets)
}

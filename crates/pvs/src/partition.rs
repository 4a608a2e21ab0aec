//! Which cells a shard owns: shard `I` of `N` owns the cells whose index is `I mod N`
//! (interleaved, so costly districts are spread over the shards). A leaf of the crate:
//! the file header records the shard, the build computes only its cells, the merge
//! checks that every cell is owned exactly once.

use crate::error::PvsError;
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

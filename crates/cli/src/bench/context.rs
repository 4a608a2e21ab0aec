//! What the bench's sections share without depending on one another: the scenes under
//! test and the part of the bench a section writes to (the suite it reads, the notes it
//! leaves for the report, the log).

use super::suite::Suite;
use sightline_scene::Scene;
use std::sync::Arc;

/// A scene under test and the name the report gives it.
pub struct NamedScene {
    pub name: String,
    pub scene: Arc<Scene>,
}

/// A section's view of the bench.
pub struct BenchContext<'a> {
    pub suite: &'a Suite,
    /// Notes for the report (a skipped scene, a bug found).
    pub notes: &'a mut Vec<String>,
    pub quiet: bool,
}

impl BenchContext<'_> {
    pub fn log(&self, msg: &str) {
        if !self.quiet {
            eprintln!("bench: {msg}");
        }
    }
}

//! `sightline bench`: the papers' experiments on our scenes, with a Markdown report,
//! PNG plots and a JSON of every raw figure.
//!
//! Every method is driven through the one `VisibilityMethod` trait, so the suite grows
//! as methods land; a method that is not available is listed as such, never replaced.
//! `missed` and `over` are measured against the sampled ground truth, computed once per
//! cell and shared by all methods.

mod context;
mod experiments;
mod from_point;
mod indoor;
mod machine;
mod meshes;
mod plots;
mod report;
mod suite;
mod vis_reference;

pub use experiments::{run, Sections};
pub use indoor::find_levels;
pub use meshes::MeshLevel;
pub use suite::Suite;
pub use vis_reference::detect_on_path as detect_vis_reference;

//! `sampled`: the aggressive visible set from sample viewpoints (survey §7.6) — the
//! ground truth of [`crate::check`], exposed as a method. It is **not conservative**: it can only
//! miss objects (seen through gaps no sample found), never invent them. See
//! [`crate::check`] for the sampling (stratified viewpoints, six cube faces per
//! viewpoint rendered into id buffers, targeted rays for the objects still unseen).
//!
//! Parameters: `samples` (viewpoints per cell) and `resolution_px` (cube-face side);
//! defaults from [`TruthOptions::default`].

use sightline_core::check::{TruthOptions, TruthScene};
use sightline_core::{MethodError, SampledOptions, VisibilityMethod};
use sightline_geom::ViewCell;
use sightline_scene::Scene;
use std::sync::Arc;

/// The sampled method prepared for a scene.
pub(crate) struct Sampled {
    truth: TruthScene,
    opts: TruthOptions,
}

impl Sampled {
    pub(crate) fn new(scene: &Scene, opts: TruthOptions) -> Self {
        Sampled {
            truth: TruthScene::new(scene),
            opts,
        }
    }
}

/// Prepare `sampled` for `scene`.
pub(crate) fn create(
    scene: Arc<Scene>,
    opts: &SampledOptions,
) -> Result<Box<dyn VisibilityMethod>, MethodError> {
    let mut t = TruthOptions::default();
    if let Some(r) = opts.resolution_px {
        t.resolution_px = r;
    }
    if let Some(s) = opts.samples {
        t.samples = s;
    }
    Ok(Box::new(Sampled::new(&scene, t)))
}

impl VisibilityMethod for Sampled {
    fn name(&self) -> &'static str {
        "sampled"
    }

    fn is_conservative(&self) -> bool {
        false
    }

    fn params(&self) -> Vec<(String, String)> {
        vec![
            ("samples".into(), self.opts.samples.to_string()),
            ("resolution_px".into(), self.opts.resolution_px.to_string()),
            (
                "targeted_rays_per_object".into(),
                self.opts.targeted_rays_per_object.to_string(),
            ),
            ("seed".into(), self.opts.seed.to_string()),
        ]
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        Ok(self.truth.ground_truth(cell, &self.opts).visible)
    }
}

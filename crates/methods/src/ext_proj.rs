//! Method module (to be implemented).

use crate::{MethodError, MethodOptions, VisibilityMethod};
use sightline_scene::Scene;
use std::sync::Arc;

/// Prepare this module's method `name` for `scene`.
pub fn create(
    name: &'static str,
    scene: Arc<Scene>,
    opts: &MethodOptions,
) -> Result<Box<dyn VisibilityMethod>, MethodError> {
    let _ = (scene, opts);
    Err(MethodError::NotImplemented(name.to_string()))
}

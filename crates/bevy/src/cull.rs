//! The culling system: locate the camera, decode its cell's row when the cell changes,
//! prefetch the rows around it, and set [`Visibility`] on the mapped entities.

use crate::{visibility, ActivePvs, PvsAsset, PvsCamera, PvsIds, SightlineSettings};
use bevy::asset::Assets;
use bevy::camera::visibility::Visibility;
use bevy::ecs::change_detection::Ref;
use bevy::ecs::prelude::*;
use bevy::transform::components::GlobalTransform;
use sightline_runtime::{Pvs, Query as RowQuery};
use std::sync::Arc;

/// What the culling decided in the last frame.
#[derive(Resource, Debug, Default)]
pub struct PvsView {
    cell: Option<u32>,
    culling: bool,
    visible: Vec<u32>,
    neighbours: Vec<u32>,
    error: Option<String>,
}

impl PvsView {
    /// The camera's cell (`None`: no file loaded, or the camera is outside every cell).
    pub fn cell(&self) -> Option<u32> {
        self.cell
    }

    /// Whether entities outside [`PvsView::visible`] are hidden. `false` when the camera
    /// has no cell or its row could not be read: then every entity is shown.
    pub fn culling(&self) -> bool {
        self.culling
    }

    /// The PVS of the camera's cell: sorted object ids (empty when not culling).
    pub fn visible(&self) -> &[u32] {
        &self.visible
    }

    /// The cells whose rows were prefetched (the cells touching the camera's cell).
    pub fn neighbours(&self) -> &[u32] {
        &self.neighbours
    }

    /// Why the camera's row could not be read, if it could not (a corrupt block, a cell
    /// the file does not store).
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// Whether an entity standing for `ids` is shown.
    pub fn shows(&self, ids: &[u32]) -> bool {
        !self.culling || ids.iter().any(|id| self.visible.binary_search(id).is_ok())
    }
}

#[derive(Default)]
pub(crate) struct CullState {
    pvs: Option<Arc<Pvs>>,
    query: RowQuery,
}

pub(crate) fn cull(
    settings: Res<SightlineSettings>,
    active: Option<Res<ActivePvs>>,
    assets: Res<Assets<PvsAsset>>,
    cameras: Query<&GlobalTransform, With<PvsCamera>>,
    mut objects: Query<(Ref<PvsIds>, &mut Visibility)>,
    mut view: ResMut<PvsView>,
    mut state: Local<CullState>,
) {
    let view = &mut *view;
    let Some(pvs) = active
        .and_then(|a| assets.get(&a.0))
        .map(|a| a.pvs().clone())
    else {
        if state.pvs.take().is_some() || view.culling {
            *view = PvsView::default();
            for (_, mut vis) in &mut objects {
                vis.set_if_neq(Visibility::Inherited);
            }
        }
        return;
    };
    let cell = cameras
        .iter()
        .next()
        .and_then(|t| pvs.locate(settings.axes.to_sightline(t.translation())));
    let new_file = !state.pvs.as_ref().is_some_and(|p| Arc::ptr_eq(p, &pvs));
    let refresh = new_file || cell != view.cell;
    if refresh {
        let q = &mut state.query;
        view.cell = cell;
        view.error = None;
        view.culling = match cell {
            Some(c) => match pvs.visible_into(q, c, &mut view.visible) {
                Ok(()) => true,
                Err(e) => {
                    view.error = Some(e.to_string());
                    false
                }
            },
            None => false,
        };
        if !view.culling {
            view.visible.clear();
        }
        view.neighbours.clear();
        if let Some(c) = cell {
            pvs.neighbours_into(c, &mut view.neighbours);
            // Decoding a neighbour's row leaves its data blocks in the query's cache: the
            // row is at hand when the camera crosses over. A row that fails is reported
            // when the camera gets there.
            for &n in &view.neighbours {
                if pvs.is_stored(n) {
                    let _ = pvs.visible(q, n);
                }
            }
        }
        state.pvs = Some(pvs);
    }
    for (ids, mut vis) in &mut objects {
        if refresh || ids.is_changed() {
            vis.set_if_neq(visibility(view.shows(ids.ids())));
        }
    }
}

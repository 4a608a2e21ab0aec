//! Test fixtures: a grid scene and a cheap deterministic method with PVS-like sets
//! (objects near the cell plus a sparse far field), so that neighbouring cells have
//! similar, not identical, sets.
#![allow(dead_code)]

use sightline_geom::{DVec2, Polygon, ViewCell};
use sightline_methods::{MethodError, VisibilityMethod};
use sightline_scene::{Object, Scene};
use std::sync::Arc;

/// `side × side` blocks of 8 m on a 10 m pitch.
pub fn grid_scene(side: usize) -> Scene {
    let mut objects = Vec::new();
    for j in 0..side {
        for i in 0..side {
            let p = DVec2::new(i as f64 * 10.0, j as f64 * 10.0);
            let h = 5.0 + ((i * 7 + j * 13) % 11) as f64;
            objects.push(Object::block(
                None,
                Polygon::rect(p, p + DVec2::splat(8.0)),
                0.0,
                h,
            ));
        }
    }
    Scene::from_objects(objects)
}

/// `nx × ny` cells of `size` metres from the origin.
pub fn grid_cells(nx: usize, ny: usize, size: f64) -> Vec<ViewCell> {
    (0..ny)
        .flat_map(|j| (0..nx).map(move |i| (i, j)))
        .map(|(i, j)| {
            ViewCell::from_array([
                i as f64 * size,
                j as f64 * size,
                1.5,
                (i + 1) as f64 * size,
                (j + 1) as f64 * size,
                2.0,
            ])
            .unwrap()
        })
        .collect()
}

/// Objects whose centre lies within `radius` of the cell centre, plus every object
/// whose id hashes into a sparse far field that varies slowly with the cell.
pub struct Nearby {
    pub scene: Arc<Scene>,
    pub radius: f64,
}

impl VisibilityMethod for Nearby {
    fn name(&self) -> &'static str {
        "nearby"
    }

    fn params(&self) -> Vec<(String, String)> {
        vec![("radius".into(), self.radius.to_string())]
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        let c = cell.center();
        let band = (c.x / 40.0).floor() as i64 + (c.y / 40.0).floor() as i64 * 7;
        Ok(self
            .scene
            .objects
            .iter()
            .enumerate()
            .filter(|(i, o)| {
                let oc = o.bounds.center();
                let d = ((oc.x - c.x).powi(2) + (oc.y - c.y).powi(2)).sqrt();
                d < self.radius || (*i as i64 * 31 + band) % 23 == 0
            })
            .map(|(i, _)| i as u32)
            .collect())
    }
}

pub fn nearby(scene: &Arc<Scene>) -> Nearby {
    Nearby {
        scene: scene.clone(),
        radius: 45.0,
    }
}

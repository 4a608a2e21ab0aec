//! Scene model of sightline: objects with ids and names, 2.5D blocks, flat
//! ground polygons and triangle meshes, each with an *outer* 2.5D bound (used when the
//! object is an occludee) and an *inner* 2.5D bound (used when it occludes).
//!
//! ```
//! use sightline_scene::{Scene, Object};
//! use sightline_geom::{Polygon, DVec2};
//! let wall = Object::block(Some("wall".into()), Polygon::rect(DVec2::new(0.0, 0.0), DVec2::new(10.0, 1.0)), 0.0, 8.0);
//! let scene = Scene::from_objects(vec![wall]);
//! assert_eq!(scene.objects.len(), 1);
//! assert_eq!(scene.bounds.max.z, 8.0);
//! ```

pub mod model;

pub use info::SceneInfo;
pub use model::{Geometry, Mesh, Object, ObjectKind, Prism, Scene, Warning};
pub mod cells;
pub mod clusters;
pub mod export;
pub mod generate;
pub mod import;
pub mod index;
pub mod info;
pub mod occluders;

//! Geometry kernel of sightline.
//!
//! Everything is `f64`, in metres, right-handed with **z up**. Signs that
//! decide inside/outside or left/right go through Shewchuk's robust predicates
//! ([`orient2d`]); polygon booleans go through `i_overlay` on an explicit 1 mm grid
//! ([`boolean`]), so callers know how far a result may move and can round it in the
//! conservative direction.
//!
//! ```
//! use sightline_geom::{Polygon, DVec2, ViewCell};
//! let square = Polygon::rect(DVec2::new(0.0, 0.0), DVec2::new(10.0, 10.0));
//! assert_eq!(square.area(), 100.0);
//! let cell: ViewCell = "-5,2,1.5,5,12,2".parse().unwrap();
//! assert_eq!(cell.size().x, 10.0);
//! ```

pub mod aabb;
pub mod boolean;
pub mod cell;
pub mod grid;
pub mod kdtree;
pub mod polygon;
pub mod predicates;

pub use aabb::{Aabb2, Aabb3};
pub use cell::{ParseBoxError, ViewCell};
pub use glam::{DVec2, DVec3};
pub use grid::UniformGrid;
pub use polygon::{Polygon, Ring};
pub use predicates::{orient2d, Orientation};

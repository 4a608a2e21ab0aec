//! The visibility core of sightline, below every method family: what a method is
//! ([`VisibilityMethod`]), the one registry of methods ([`Method`]) with their typed
//! options ([`Options`]) and errors ([`MethodError`]), the viewcells a method answers for
//! ([`Cell`]: a box, a convex polyhedron such as a BSP leaf, or a cell of an automatic
//! cell complex) and the ground truth every conservative method is checked against
//! ([`check`]).
//!
//! The families live in crates above this one (`sightline-methods`: erosion, dual ray
//! space, extended projections, the sampled truth; further families in crates of their
//! own) and depend only downwards: on this crate and on the geometry, scene and raster
//! crates below it. A family implements [`VisibilityMethod`]; the registry entry in
//! [`Method`] names it once, with its paper, its guarantee and its knobs.
//!
//! The guarantee of every conservative method: it may report a hidden object as
//! visible, never a visible object as hidden.
//!
//! ```
//! use sightline_core::{Method, MethodOptions, Options};
//! let m: Method = "dual-ray".parse().unwrap();
//! let opts = MethodOptions { resolution_px: Some(64), ..MethodOptions::default() };
//! let Options::DualRay(d) = m.options(&opts).unwrap() else { unreachable!() };
//! assert_eq!(d.resolution_px, Some(64));
//! assert!(d.seed_rays && d.hidden_boxes && !d.virtual_occluders);
//! ```

// `!(a < b)` is the NaN-safe way to reject bad values in geometric code: keep it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cell;
pub mod check;
mod registry;

pub use cell::{Cell, CellKind, ConvexCell, HalfSpace, VoxelCell};
pub use registry::{
    DualRayOptions, ErosionOptions, ExtProjOptions, Family, IntoMethod, Knob, Method,
    MethodOptions, Options, SampledOptions, SceneKind, METHOD_NAMES,
};

use sightline_geom::ViewCell;

/// Why a method could not be prepared or could not answer.
#[derive(Debug, thiserror::Error)]
pub enum MethodError {
    #[error("unknown method '{0}' (known: {known})", known = METHOD_NAMES.join(", "))]
    Unknown(String),
    #[error("invalid viewcell: {0}")]
    BadCell(String),
    #[error("{method}: {message}")]
    BadOption {
        method: &'static str,
        message: String,
    },
    #[error("{0}")]
    Other(String),
}

/// A visibility method prepared for one scene: built once by its family's constructor,
/// then asked for any number of viewcells, from any thread.
pub trait VisibilityMethod: Send + Sync {
    /// The method's name, as selected everywhere (`--method`, the library, the server).
    fn name(&self) -> &'static str;

    /// Whether the result is guaranteed to contain every visible object.
    fn is_conservative(&self) -> bool {
        true
    }

    /// Parameters that determine the output, as `key=value` pairs (stored in `.pvs`).
    fn params(&self) -> Vec<(String, String)> {
        Vec::new()
    }

    /// The PVS of the box `cell`: object ids, sorted ascending, without duplicates.
    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError>;

    /// The PVS of a viewcell of any kind. The default answers for the cell's bounding
    /// box, which contains the cell: every viewpoint of the cell is a viewpoint of the
    /// box, so a conservative PVS of the box is a conservative PVS of the cell. Families
    /// that know the cell's own shape (a portal solver and its leaves) answer tighter.
    fn pvs_cell(&self, cell: &Cell) -> Result<Vec<u32>, MethodError> {
        self.pvs(&cell.bounds())
    }
}

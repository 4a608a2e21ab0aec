//! `bevy_sightline`: sightline's potentially visible sets in Bevy. The camera's cell is
//! located in a `.pvs` (built offline by `sightline build`), and every entity that stands
//! for a PVS object outside that cell's PVS gets [`Visibility::Hidden`]; the others get
//! [`Visibility::Inherited`]. The PVS is conservative: it may keep a hidden object, never
//! hide a visible one, so the renderer's own frustum culling still runs on what is left.
//!
//! * [`PvsAsset`]: a `.pvs` loaded through the [`AssetServer`](bevy::asset::AssetServer)
//!   (read and checked by `sightline-runtime`, exactly as `sightline query` reads it).
//! * [`ActivePvs`]: the resource naming the `.pvs` of the level the camera walks.
//! * [`PvsCamera`]: the camera whose position picks the cell.
//! * [`PvsKey`]: maps an entity to PVS ids — an object id (a city's object, a mesh level's
//!   cluster), a source object's name, or a glTF node name. With
//!   [`SightlinePlugin::match_names`] (the default), entities with a [`Name`] such as the
//!   nodes of a glTF scene are mapped without a key: a name `12` or `cluster 12` is
//!   cluster 12, another name is looked up among the level's source objects.
//! * [`PvsView`]: what the last frame decided (cell, visible ids, prefetched neighbours).
//!
//! The culling system runs in `PostUpdate`, after transform propagation and before
//! visibility propagation, so the decision holds in the frame it is made. When the camera
//! enters a cell, the rows of the cells whose boxes touch it are decoded too (prefetch):
//! their data blocks are then in the query cache when the camera crosses over.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_sightline::{ActivePvs, PvsCamera, SightlinePlugin};
//!
//! fn setup(mut commands: Commands, assets: Res<AssetServer>) {
//!     commands.insert_resource(ActivePvs(assets.load("level.pvs")));
//!     commands.spawn((Camera3d::default(), Transform::default(), PvsCamera));
//! }
//!
//! App::new()
//!     .add_plugins((DefaultPlugins, SightlinePlugin::default()))
//!     .add_systems(Startup, setup)
//!     .run();
//! ```

mod asset;
mod cull;
mod key;

pub use asset::{PvsAsset, PvsLoadError, PvsLoader};
pub use cull::PvsView;
pub use key::{cluster_number, PvsIds, PvsKey};

use bevy::app::{App, Plugin, PostUpdate};
use bevy::asset::{AssetApp, Handle};
use bevy::camera::visibility::{Visibility, VisibilitySystems};
use bevy::ecs::prelude::*;
use bevy::math::Vec3;
use bevy::transform::TransformSystems;

#[cfg(doc)]
use bevy::ecs::name::Name;

/// Loads `.pvs` assets and culls the entities mapped to PVS ids against the PVS of the
/// [`PvsCamera`]'s cell.
#[derive(Clone, Debug)]
pub struct SightlinePlugin {
    /// How Bevy's world coordinates turn into the `.pvs`'s.
    pub axes: Axes,
    /// Map entities with a [`Name`] and no [`PvsKey`] by that name (glTF nodes).
    pub match_names: bool,
}

impl Default for SightlinePlugin {
    fn default() -> Self {
        SightlinePlugin {
            axes: Axes::YUp,
            match_names: true,
        }
    }
}

/// Bevy's frame against sightline's (metres, right-handed, z up).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Axes {
    /// Bevy and glTF (y up): Bevy's `(x, y, z)` is sightline's `(x, −z, y)`, the inverse
    /// of the turn sightline's glTF importer applies.
    #[default]
    YUp,
    /// The world is already z up (a level placed as sightline saw it).
    ZUp,
}

impl Axes {
    /// A point of Bevy's world in the `.pvs`'s frame.
    pub fn to_sightline(self, p: Vec3) -> [f64; 3] {
        let (x, y, z) = (p.x as f64, p.y as f64, p.z as f64);
        match self {
            Axes::YUp => [x, -z, y],
            Axes::ZUp => [x, y, z],
        }
    }

    /// A point of the `.pvs`'s frame in Bevy's world.
    pub fn to_bevy(self, p: [f64; 3]) -> Vec3 {
        let [x, y, z] = p.map(|v| v as f32);
        match self {
            Axes::YUp => Vec3::new(x, z, -y),
            Axes::ZUp => Vec3::new(x, y, z),
        }
    }
}

/// The plugin's settings, as a resource.
#[derive(Resource, Clone, Debug)]
pub struct SightlineSettings {
    pub axes: Axes,
    pub match_names: bool,
}

/// The `.pvs` of the level being walked. Without it (or until it has loaded, or while the
/// camera is outside every cell) every mapped entity is shown.
#[derive(Resource, Clone, Debug)]
pub struct ActivePvs(pub Handle<PvsAsset>);

/// The camera whose position picks the cell (the first one found if there are several).
#[derive(Component, Clone, Copy, Debug, Default)]
pub struct PvsCamera;

/// The plugin's systems, in `PostUpdate`: keys resolved to ids, then the culling.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SightlineSystems {
    /// [`PvsKey`] and [`Name`] turned into [`PvsIds`].
    Resolve,
    /// [`Visibility`] set from the PVS of the camera's cell.
    Cull,
}

impl Plugin for SightlinePlugin {
    fn build(&self, app: &mut App) {
        app.init_asset::<PvsAsset>()
            .register_asset_loader(PvsLoader)
            .insert_resource(SightlineSettings {
                axes: self.axes,
                match_names: self.match_names,
            })
            .init_resource::<PvsView>()
            .configure_sets(
                PostUpdate,
                (SightlineSystems::Resolve, SightlineSystems::Cull)
                    .chain()
                    .after(TransformSystems::Propagate)
                    .before(VisibilitySystems::VisibilityPropagate),
            )
            .add_systems(
                PostUpdate,
                (
                    key::resolve.in_set(SightlineSystems::Resolve),
                    cull::cull.in_set(SightlineSystems::Cull),
                ),
            );
    }
}

/// The visibility the plugin gives an entity: shown entities inherit their parent's.
pub(crate) fn visibility(shown: bool) -> Visibility {
    if shown {
        Visibility::Inherited
    } else {
        Visibility::Hidden
    }
}

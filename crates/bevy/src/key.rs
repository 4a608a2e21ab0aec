//! Which PVS objects an entity stands for: [`PvsKey`] (or a glTF node's [`Name`]) resolved
//! against the active `.pvs` into [`PvsIds`].

use crate::{ActivePvs, PvsAsset, SightlineSettings};
use bevy::asset::Assets;
use bevy::camera::visibility::Visibility;
use bevy::ecs::change_detection::Ref;
use bevy::ecs::name::Name;
use bevy::ecs::prelude::*;
use sightline_runtime::Pvs;
use std::sync::Arc;

/// What an entity stands for in the PVS. An entity is shown when any of its ids is in the
/// PVS of the camera's cell; a key that matches no id leaves the entity alone (shown).
#[derive(Component, Clone, Debug, PartialEq, Eq)]
pub enum PvsKey {
    /// An object id of the `.pvs`: a city's object (in `sightline info`'s order), a mesh
    /// level's cluster.
    Id(u32),
    /// A mesh level's source object by name (an OBJ group, a glTF node of the level that
    /// was built): all of its clusters.
    Source(String),
    /// A glTF node name: `12` or `cluster 12` (`cluster_12`, `cluster-12`, `cluster#12`)
    /// is cluster 12, any other name a source object's name.
    NodeName(String),
}

impl PvsKey {
    /// The ids this key stands for in `asset`, ascending.
    pub fn ids(&self, asset: &PvsAsset) -> Vec<u32> {
        let pvs: &Pvs = asset.pvs();
        let known = |id: u32| id < pvs.object_count();
        match self {
            PvsKey::Id(id) => Some(*id).filter(|&i| known(i)).into_iter().collect(),
            PvsKey::Source(name) => asset.source_clusters(name).to_vec(),
            PvsKey::NodeName(name) => match cluster_number(name) {
                Some(id) => Some(id).filter(|&i| known(i)).into_iter().collect(),
                None => asset.source_clusters(name).to_vec(),
            },
        }
    }
}

/// The cluster a node name stands for: digits alone, or `cluster` (any case) followed by
/// digits, possibly after one of ` `, `_`, `-`, `#`.
pub fn cluster_number(name: &str) -> Option<u32> {
    let name = name.trim();
    let digits = match name.get(..7) {
        Some(head) if head.eq_ignore_ascii_case("cluster") => {
            let rest = &name[7..];
            rest.strip_prefix([' ', '_', '-', '#']).unwrap_or(rest)
        }
        _ => name,
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// The PVS ids an entity stands for, resolved by the plugin from its [`PvsKey`] or
/// [`Name`] (ascending, never empty).
#[derive(Component, Clone, Debug, PartialEq, Eq)]
#[require(Visibility)]
pub struct PvsIds(pub(crate) Vec<u32>);

impl PvsIds {
    pub fn ids(&self) -> &[u32] {
        &self.0
    }
}

/// Resolves keys and names: all of them when the active file changed (loaded, reloaded,
/// switched), else those added or changed since the last run.
#[allow(clippy::too_many_arguments, clippy::type_complexity)] // as Bevy systems are
pub(crate) fn resolve(
    mut commands: Commands,
    settings: Res<SightlineSettings>,
    active: Option<Res<ActivePvs>>,
    assets: Res<Assets<PvsAsset>>,
    keyed: Query<(Entity, Ref<PvsKey>, Option<&PvsIds>)>,
    named: Query<(Entity, Ref<Name>, Option<&PvsIds>), Without<PvsKey>>,
    mut unkeyed: RemovedComponents<PvsKey>,
    mut last: Local<Option<Arc<Pvs>>>,
) {
    let Some(asset) = active.and_then(|a| assets.get(&a.0)) else {
        *last = None;
        return;
    };
    let all = !last.as_ref().is_some_and(|p| Arc::ptr_eq(p, asset.pvs()));
    *last = Some(asset.pvs().clone());
    let mut set = |e: Entity, key: &PvsKey, had: Option<&PvsIds>| {
        let ids = key.ids(asset);
        match (ids.is_empty(), had) {
            (true, Some(_)) => {
                // No longer culled: shown, as an unmapped entity is.
                commands
                    .entity(e)
                    .remove::<PvsIds>()
                    .insert(Visibility::Inherited);
            }
            (true, None) => {}
            (false, Some(old)) if old.0 == ids => {}
            (false, _) => {
                commands.entity(e).insert(PvsIds(ids));
            }
        }
    };
    for (e, key, had) in &keyed {
        if all || key.is_changed() {
            set(e, &key, had);
        }
    }
    let unkeyed: Vec<Entity> = unkeyed.read().collect();
    for (e, name, had) in &named {
        let by_name = settings.match_names && (all || name.is_changed() || unkeyed.contains(&e));
        if by_name {
            set(e, &PvsKey::NodeName(name.as_str().to_owned()), had);
        } else if !settings.match_names && unkeyed.contains(&e) && had.is_some() {
            set(e, &PvsKey::NodeName(String::new()), had);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::cluster_number;

    #[test]
    fn node_names_that_are_cluster_ids() {
        assert_eq!(cluster_number("12"), Some(12));
        assert_eq!(cluster_number("cluster 12"), Some(12));
        assert_eq!(cluster_number("Cluster_7"), Some(7));
        assert_eq!(cluster_number("cluster-0"), Some(0));
        assert_eq!(cluster_number("cluster#3"), Some(3));
        assert_eq!(cluster_number("cluster12"), Some(12));
        assert_eq!(cluster_number(" 4 "), Some(4));
        for name in [
            "",
            "cluster",
            "cluster ",
            "wall2",
            "12a",
            "-3",
            "cluster  1",
            "99999999999",
        ] {
            assert_eq!(cluster_number(name), None, "{name:?}");
        }
    }
}

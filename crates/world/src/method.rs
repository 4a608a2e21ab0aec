//! A `--method` name resolved against the kind of scene, once: the default of each kind
//! and the families that work on it (`Method::works_on`; the registry of
//! `sightline-core` stays the one list of methods, `docs/families.md`).

use crate::kind::{kind_word, kind_words};
use sightline_core::{Family, Method, SceneKind};
use std::path::Path;

/// The method a command uses on a scene of `kind` when none is named: `erosion` on a
/// city, `portals` on a BSP level (`map`), `volumetric` (walkable viewcells) on a mesh
/// level (`build`, `check`). `serve` prefers faster ones (`dual-ray`, `portals-fast`).
pub fn default_method(kind: SceneKind) -> Method {
    match kind {
        SceneKind::City => Method::Erosion,
        SceneKind::Bsp => Method::Portals,
        SceneKind::Mesh => Method::Volumetric,
    }
}

/// The method `serve` answers with when none is named: on-line `dual-ray` on a city,
/// a BSP level's PVS built in memory with `portals-fast` (about as long as a build),
/// a mesh level's walkable viewcells (`volumetric`, as `build`).
pub fn serving_method(kind: SceneKind) -> Method {
    match kind {
        SceneKind::City => Method::DualRay,
        SceneKind::Bsp => Method::PortalsFast,
        SceneKind::Mesh => Method::Volumetric,
    }
}

/// `name` (or the kind's default) as a method that works on a scene of `kind` at `path`
/// (named in the error). An unknown name lists the known ones (the registry's error).
pub fn resolve(kind: SceneKind, path: &Path, name: Option<&str>) -> anyhow::Result<Method> {
    let Some(name) = name else {
        return Ok(default_method(kind));
    };
    let m: Method = name.parse()?;
    if m.works_on(kind) {
        return Ok(m);
    }
    let kinds: Vec<&str> = [SceneKind::City, SceneKind::Bsp, SceneKind::Mesh]
        .into_iter()
        .filter(|&k| m.works_on(k))
        .map(kind_words)
        .collect();
    anyhow::bail!(
        "{name} works on {}; {} is {}",
        kinds.join(" and "),
        path.display(),
        kind_word(kind)
    )
}

/// Whether `m` answers on the level's own cells (BSP leaves, automatic cells, walkable
/// viewcells) rather than on viewcell boxes given by the user.
pub fn on_level_cells(m: Method) -> bool {
    matches!(m.family(), Family::Portals | Family::Volumetric)
}

/// `portals` → the full flow, `portals-fast` → the flood; `None` for other methods.
pub fn portal_mode(m: Method) -> Option<sightline_portals::Mode> {
    match m {
        Method::Portals => Some(sightline_portals::Mode::Full),
        Method::PortalsFast => Some(sightline_portals::Mode::Fast),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sightline_core::METHOD_NAMES;

    const KINDS: [SceneKind; 3] = [SceneKind::City, SceneKind::Bsp, SceneKind::Mesh];

    #[test]
    fn every_method_on_every_kind_resolves_as_works_on_says() {
        for name in METHOD_NAMES {
            let m: Method = name.parse().unwrap();
            for kind in KINDS {
                let r = resolve(kind, Path::new("scene"), Some(name));
                assert_eq!(r.is_ok(), m.works_on(kind), "{name} on {kind:?}: {r:?}");
                if let Ok(got) = r {
                    assert_eq!(got, m);
                } else {
                    let e = r.unwrap_err().to_string();
                    assert!(e.starts_with(&format!("{name} works on ")), "{e}");
                    assert!(e.ends_with(kind_word(kind)), "{e}");
                    assert_eq!(e.lines().count(), 1, "{e}");
                }
            }
        }
    }

    #[test]
    fn defaults_are_the_kinds_own_and_work_on_them() {
        assert_eq!(default_method(SceneKind::City), Method::Erosion);
        assert_eq!(default_method(SceneKind::Bsp), Method::Portals);
        assert_eq!(default_method(SceneKind::Mesh), Method::Volumetric);
        for kind in KINDS {
            let d = resolve(kind, Path::new("scene"), None).unwrap();
            assert_eq!(d, default_method(kind));
            assert!(d.works_on(kind));
            assert!(serving_method(kind).works_on(kind));
        }
    }

    #[test]
    fn an_unknown_name_lists_the_known_ones() {
        let e = resolve(SceneKind::City, Path::new("c.geojson"), Some("dual_ray"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown method 'dual_ray'"), "{e}");
        for name in METHOD_NAMES {
            assert!(e.contains(name), "{name} missing from {e}");
        }
    }

    #[test]
    fn portal_modes_and_level_cells() {
        assert_eq!(
            portal_mode(Method::Portals),
            Some(sightline_portals::Mode::Full)
        );
        assert_eq!(
            portal_mode(Method::PortalsFast),
            Some(sightline_portals::Mode::Fast)
        );
        for name in METHOD_NAMES {
            let m: Method = name.parse().unwrap();
            // A method on the level's cells never works on a city.
            assert!(
                !(on_level_cells(m) && m.works_on(SceneKind::City)),
                "{name}"
            );
        }
    }
}

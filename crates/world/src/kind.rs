//! Which kind of scene a path holds, from its extension: the one place that says so
//! (`sightline_core::SceneKind`; the importers in `sightline-scene` read the bytes).

use sightline_core::SceneKind;
use std::path::Path;

/// Extensions of mesh levels (any case).
const MESH_EXTENSIONS: [&str; 3] = ["obj", "gltf", "glb"];

/// The kind of scene at `path`: a `.bsp` is a BSP level, a `.obj`, `.gltf` or `.glb` a
/// mesh level, anything else a city (GeoJSON, CityJSON, OSM, …).
///
/// ```
/// use sightline_core::SceneKind;
/// use std::path::Path;
/// assert_eq!(sightline_world::kind_of(Path::new("dm1.BSP")), SceneKind::Bsp);
/// assert_eq!(sightline_world::kind_of(Path::new("level.glb")), SceneKind::Mesh);
/// assert_eq!(sightline_world::kind_of(Path::new("lyon.geojson")), SceneKind::City);
/// ```
pub fn kind_of(path: &Path) -> SceneKind {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if ext.eq_ignore_ascii_case("bsp") {
        SceneKind::Bsp
    } else if MESH_EXTENSIONS.iter().any(|m| ext.eq_ignore_ascii_case(m)) {
        SceneKind::Mesh
    } else {
        SceneKind::City
    }
}

/// The kind in words, plural, for messages ("BSP levels (.bsp)").
pub fn kind_words(kind: SceneKind) -> &'static str {
    match kind {
        SceneKind::City => "cities (and any scene with a cells file)",
        SceneKind::Bsp => "BSP levels (.bsp)",
        SceneKind::Mesh => "mesh levels (.obj, .gltf, .glb)",
    }
}

/// The kind in words, singular with its article, for messages ("a BSP level").
pub fn kind_word(kind: SceneKind) -> &'static str {
    match kind {
        SceneKind::City => "a city",
        SceneKind::Bsp => "a BSP level",
        SceneKind::Mesh => "a mesh level",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extension_decides_the_kind_in_any_case() {
        for (path, kind) in [
            ("a/dm1.bsp", SceneKind::Bsp),
            ("E1M1.BSP", SceneKind::Bsp),
            ("level.obj", SceneKind::Mesh),
            ("level.OBJ", SceneKind::Mesh),
            ("level.gltf", SceneKind::Mesh),
            ("level.glb", SceneKind::Mesh),
            ("lyon.geojson", SceneKind::City),
            ("city.city.json", SceneKind::City),
            ("denhaag.zip", SceneKind::City),
            ("extract.osm.pbf", SceneKind::City),
            ("no-extension", SceneKind::City),
            ("bsp", SceneKind::City),
        ] {
            assert_eq!(kind_of(Path::new(path)), kind, "{path}");
        }
    }
}

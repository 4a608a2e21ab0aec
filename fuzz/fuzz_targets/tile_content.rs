//! The 3D Tiles content parsers (GLB with EXT_mesh_features / EXT_structural_metadata,
//! b3dm with feature and batch tables) on arbitrary bytes: an error or a scene, never a
//! panic, a hang or an unbounded allocation. Seeds: `seeds/tile_content/` (GLB and b3dm
//! written by `sightline tiles` and the import tests).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = sightline_scene::import::tileset::parse_content(data);
});

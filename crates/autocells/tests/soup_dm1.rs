//! dm1 read as a triangle soup (its world faces, no tree) through the automatic cells,
//! judged by the ray oracle through the level's own BSP tree: 0 misses, and the PVS
//! culls (issue #39 item 5).

use sightline_autocells::soup::{bsp_soup, judge, JudgeOptions};
use sightline_autocells::{AutoCells, Options};
use sightline_portals::{Mode, Portals};
use sightline_scene::import::bsp::load_bsp;

#[test]
fn dm1_soup_conservative_and_culls() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/quake/dm1.bsp");
    let level = load_bsp(&path).expect("data/quake/dm1.bsp loads");
    let soup = bsp_soup(&level);
    assert_eq!(soup.faces.len() + soup.liquid_faces, level.faces.len());
    let opts = Options {
        smallest_hole: Some(SMALLEST_HOLE),
        max_voxels: 1 << 26,
        full: false,
        ..Options::default()
    };
    let auto = AutoCells::build(&soup.scene, &opts).expect("dm1's soup cuts into cells");
    assert!(auto.report.leak.is_none(), "{:?}", auto.report.leak);
    let portals = Portals::build(&level).expect("dm1 portalizes");
    let j = judge(
        &level,
        &soup,
        &auto,
        &portals,
        &JudgeOptions {
            viewpoints: 6,
            cell_points: 16,
            segments: 4,
            segments_vis: 64,
            bsp_mode: Mode::Fast,
            seed: 11,
        },
    );
    assert_eq!(j.viewpoints.len(), 6);
    assert_eq!(j.viewpoints_in_solid, 0, "open-leaf points in solid voxels");
    assert!(j.segments > 2000, "{} segments", j.segments);
    assert_eq!(j.missed, 0, "{:?}", j.misses);
    for v in &j.viewpoints {
        assert!(v.ours <= soup.faces.len());
    }
    // Not everything: some face is culled from most viewpoints.
    let most = j.viewpoints.len().div_ceil(2) as u32 + 1;
    assert!(
        j.culled_by.iter().any(|&c| c >= most),
        "no face culled from {most} of {} viewpoints",
        j.viewpoints.len()
    );
    assert!(j.viewpoints.iter().any(|v| v.ours < soup.faces.len()));
}

/// Quake units (a player is 32 wide): walls thicker than 2 h = 8 units hold a solid voxel
/// wherever the grid falls; on dm1 that is all but 33 of the 1,146 faces with a wall
/// within 64 units behind them (`soup::wall_thickness`).
const SMALLEST_HOLE: f64 = 4.0;

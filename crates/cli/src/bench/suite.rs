//! The sizes and counts of a benchmark suite (`quick`, `full`), read by the experiments
//! and written into the report.

use serde::Serialize;
use std::path::PathBuf;

/// A run of one cell longer than this is not repeated: at that length the run-to-run
/// noise is a few per cent, and repeating the slow methods dominated the suite's time.
pub(crate) const NO_REPEAT_MS: f64 = 500.0;

/// Sizes and counts of one suite.
#[derive(Clone, Debug, Serialize)]
pub struct Suite {
    pub name: String,
    pub seed: u64,
    pub city_buildings: usize,
    pub cell_sizes_m: Vec<f64>,
    pub cells_per_setting: usize,
    pub timing_repeats: usize,
    pub metropolis_buildings: usize,
    pub dual_ray_cell_sizes_m: Vec<f64>,
    pub dual_ray_resolutions: Vec<u32>,
    pub ext_proj_resolutions: Vec<u32>,
    pub forest_trees: usize,
    pub sweep_planes: Vec<u32>,
    pub scaling_buildings: Vec<usize>,
    /// Cells per scene size of the scaling experiment (its slow methods take seconds
    /// per cell on the larger metropolises). A method's first cell also pays its one-time
    /// preparation (erosion's rasters): with 2 cells the median includes it.
    pub scaling_cells: usize,
    pub truth_samples: Option<u32>,
    pub truth_resolution_px: Option<u32>,
    /// Source leaves per level checked against the ray oracle (indoor section).
    pub indoor_sources: usize,
    /// From-point section: frames per scene, buffer size, every how many frames the
    /// full-resolution reference and the item-buffer truth run, frames of the walk plot.
    pub from_point_frames: usize,
    pub from_point_size: (u32, u32),
    pub from_point_full_every: usize,
    pub from_point_truth_every: usize,
    pub from_point_walk_frames: usize,
    /// Scene files the from-point section adds when present and not given with
    /// `--scene` (relative to the working directory: the repository's `data/`).
    pub from_point_scenes: Vec<String>,
    /// Mesh section: walkable viewcells per level whose PVS is computed, spread over
    /// the list (`None`: all), and how many of them the truth judges.
    pub mesh_viewcells: Option<usize>,
    pub mesh_judged: usize,
    /// Run only these experiments (`bench --only`; names as in the report's footer,
    /// case-insensitive); all when `None`.
    pub only: Option<Vec<String>>,
    /// Indoor section: a reference `vis` (ericw-tools) run beside `sightline vis` on
    /// every level (`bench --vis-reference`, or `vis` on `PATH`); none: against the
    /// levels' shipped rows only.
    pub vis_reference: Option<PathBuf>,
    /// Indoor section beside the reference: a folder of `LEVEL.prt` files both tools
    /// start from (`--vis-prt`); our own portals, written as PRT1, otherwise.
    pub vis_prt: Option<PathBuf>,
}

impl Suite {
    pub fn named(name: &str) -> anyhow::Result<Suite> {
        match name {
            "quick" => Ok(Suite {
                name: "quick".into(),
                seed: 1,
                city_buildings: 500,
                cell_sizes_m: vec![10.0, 25.0, 50.0, 100.0, 200.0],
                cells_per_setting: 4,
                timing_repeats: 3,
                metropolis_buildings: 10_000,
                dual_ray_cell_sizes_m: vec![50.0, 100.0, 300.0],
                dual_ray_resolutions: vec![16, 32, 64, 128, 256],
                ext_proj_resolutions: vec![64, 128, 256, 512, 1024],
                forest_trees: 80,
                sweep_planes: vec![1, 5, 15],
                scaling_buildings: vec![1_000, 10_000],
                scaling_cells: 2,
                truth_samples: None,
                truth_resolution_px: None,
                indoor_sources: 20,
                from_point_frames: 40,
                from_point_size: (1920, 1080),
                from_point_full_every: 4,
                from_point_truth_every: 4,
                from_point_walk_frames: 60,
                from_point_scenes: vec!["data/lyon1_bdtopo.geojson".into()],
                mesh_viewcells: Some(64),
                mesh_judged: 8,
                only: None,
                vis_reference: None,
                vis_prt: None,
            }),
            "full" => Ok(Suite {
                name: "full".into(),
                seed: 1,
                city_buildings: 500,
                cell_sizes_m: vec![10.0, 25.0, 50.0, 100.0, 200.0],
                cells_per_setting: 10,
                timing_repeats: 5,
                metropolis_buildings: 150_000,
                dual_ray_cell_sizes_m: vec![50.0, 100.0, 300.0],
                dual_ray_resolutions: vec![16, 32, 64, 128, 256],
                ext_proj_resolutions: vec![64, 128, 256, 512, 1024],
                forest_trees: 400,
                sweep_planes: vec![1, 5, 15],
                scaling_buildings: vec![1_000, 10_000, 150_000],
                scaling_cells: 4,
                truth_samples: None,
                truth_resolution_px: None,
                indoor_sources: 60,
                from_point_frames: 300,
                from_point_size: (1920, 1080),
                from_point_full_every: 5,
                from_point_truth_every: 10,
                from_point_walk_frames: 200,
                from_point_scenes: vec!["data/lyon1_bdtopo.geojson".into()],
                mesh_viewcells: None,
                mesh_judged: 20,
                only: None,
                vis_reference: None,
                vis_prt: None,
            }),
            other => anyhow::bail!("unknown suite '{other}' (known: quick, full)"),
        }
    }
}

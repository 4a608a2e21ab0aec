//! Command-line definitions (clap derive). One variant per command.

use clap::{Args, Parser, Subcommand, ValueEnum};
use sightline_geom::ViewCell;
use sightline_methods::Method;
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(name = "sightline", version, about = "Conservative potentially visible sets for cities", long_about = None, after_help = methods_help())]
pub struct Cli {
    /// Hide progress bars.
    #[arg(long, global = true)]
    pub quiet: bool,
    #[command(subcommand)]
    pub command: Command,
}

/// Coordinate reference of inputs that may be geographic.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum CrsArg {
    Auto,
    Projected,
    Wgs84,
}

#[derive(Args, Debug, Clone)]
pub struct SceneArg {
    /// Scene file: .geojson, CityJSON (.json/.city.json/.zip), .osm.pbf, .obj, .gltf/.glb, .bsp (Quake).
    pub scene: PathBuf,
    /// Coordinate reference of the input (GeoJSON/OSM): detect, projected metres, or WGS84 lon/lat.
    #[arg(long, value_enum, default_value = "auto")]
    pub crs: CrsArg,
    /// Abort on the first feature that cannot be used instead of skipping it (by default
    /// it is skipped with a counted `skipped-feature` warning naming it).
    #[arg(long)]
    pub strict: bool,
}

/// The methods `--method` takes, one line each, from the registry
/// ([`sightline_methods::Method`]): shown after the help of every command with `--method`.
pub fn methods_help() -> String {
    let width = Method::ALL
        .iter()
        .map(|m| m.name().len())
        .max()
        .unwrap_or(0);
    let mut s = String::from("Methods (--method; [keys for --set KEY=VALUE]):\n");
    for m in Method::ALL {
        let keys: Vec<&str> = m.knobs().iter().map(|k| k.key).collect();
        let keys = if keys.is_empty() {
            String::new()
        } else {
            format!(" [{}]", keys.join(", "))
        };
        s.push_str(&format!("  {:width$}  {}{keys}\n", m.name(), m.summary()));
    }
    s
}

fn parse_cell(s: &str) -> Result<ViewCell, String> {
    s.parse::<ViewCell>().map_err(|e| e.to_string())
}

fn parse_cell_pair(s: &str) -> Result<[u32; 2], String> {
    match s.split_once(',') {
        Some((a, b)) => {
            let cell = |v: &str| {
                v.trim()
                    .parse::<u32>()
                    .map_err(|_| format!("'{v}' is not a cell number"))
            };
            Ok([cell(a)?, cell(b)?])
        }
        None => Err(format!("expected A,B (two cell numbers), got '{s}'")),
    }
}

fn parse_point(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| {
            p.trim()
                .parse::<f64>()
                .map_err(|_| format!("'{p}' is not a number"))
        })
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        [_, _, _] => Err("coordinates must be finite".into()),
        _ => Err(format!("expected X,Y,Z, got {} numbers", v.len())),
    }
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run the main job end to end on an embedded default scene.
    Demo {
        /// Output folder.
        #[arg(short, long, default_value = "sightline-demo")]
        out: PathBuf,
    },
    /// Generate a scene (deterministic for a seed) as GeoJSON.
    Generate {
        #[arg(value_enum)]
        kind: GenerateKind,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Size: number of buildings (city 500, metropolis 150000) or trees (forest 500).
        #[arg(long)]
        size: Option<usize>,
        /// forest: leaf quads per tree (default 200, 1500 with --dense).
        #[arg(long)]
        leaves: Option<usize>,
        /// forest: the dense forest of the occlusion sweep (ext. proj. paper §7.2): crowns
        /// down to the ground 4 m apart, 1,500 leaves each; most trees are hidden from inside.
        #[arg(long)]
        dense: bool,
        /// Output: .geojson/.json (city, metropolis) or .obj (any kind; forest needs .obj).
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Counts, bounds and warnings of a scene.
    Info {
        #[command(flatten)]
        scene: SceneArg,
        #[arg(long)]
        json: bool,
    },
    /// Cover the scene with square viewcells.
    Cells {
        #[command(flatten)]
        scene: SceneArg,
        /// Cell side in metres (default 50; a mesh level without it gets its automatic
        /// cells).
        #[arg(long, allow_hyphen_values = true)]
        size: Option<f64>,
        /// Mesh levels with `portals`/`portals-fast`: the voxel size of the automatic
        /// cells (scene units; default automatic, see docs/methods/auto-cells.md).
        #[arg(long)]
        smallest_hole: Option<f64>,
        /// Eye-height range, `Z0:Z1`.
        #[arg(long, default_value = "1.5:2.0", allow_hyphen_values = true)]
        z: String,
        /// Keep only cells meeting this GeoJSON polygon (e.g. the streets).
        #[arg(long)]
        clip: Option<PathBuf>,
        #[arg(short, long)]
        out: PathBuf,
    },
    /// A mesh level's clusters, the ids its `.pvs` lists: as JSON (source object, box, the
    /// file's triangles) or as a binary glTF with one node per cluster named by its id.
    Clusters {
        #[command(flatten)]
        scene: SceneArg,
        /// The voxel size the level is built with (as `build`; it sets the cluster grid).
        #[arg(long, conflicts_with = "pvs")]
        smallest_hole: Option<f64>,
        /// A `.pvs` built from this level: its smallest hole, and a check that the
        /// clusters are its ids (fingerprint).
        #[arg(long)]
        pvs: Option<PathBuf>,
        /// Print the listing as JSON.
        #[arg(long)]
        json: bool,
        /// Write the listing (`.json`) or the level as binary glTF (`.glb`).
        #[arg(short, long)]
        out: Option<PathBuf>,
    },
    /// PVS of one viewcell with one method.
    #[command(after_help = methods_help())]
    Pvs {
        #[command(flatten)]
        scene: SceneArg,
        /// The viewcell `X0,Y0,Z0,X1,Y1,Z1`.
        #[arg(long, value_parser = parse_cell, allow_hyphen_values = true, required_unless_present = "at")]
        cell: Option<ViewCell>,
        /// BSP levels with `portals`/`portals-fast`: the PVS of the leaf holding `X,Y,Z`.
        #[arg(long, value_parser = parse_point, allow_hyphen_values = true, conflicts_with = "cell")]
        at: Option<[f64; 3]>,
        /// The method (listed below).
        #[arg(long, default_value = "erosion")]
        method: String,
        #[arg(long)]
        resolution: Option<u32>,
        /// ext-proj: run the occlusion sweep.
        #[arg(long)]
        sweep: bool,
        /// ext-proj --sweep: number of sweep planes per direction (default 15, §7.2).
        #[arg(long)]
        planes: Option<u32>,
        /// Any knob of the method by key, repeatable (`--set virtual_occluders=true`; the
        /// keys each method takes are listed below).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Mesh levels with `portals`/`portals-fast`: the voxel size of the automatic
        /// cells (scene units; default automatic, see docs/methods/auto-cells.md).
        #[arg(long)]
        smallest_hole: Option<f64>,
        #[arg(long)]
        json: bool,
    },
    /// Ground-truth visible set of one viewcell by dense sampling.
    Truth {
        #[command(flatten)]
        scene: SceneArg,
        #[arg(long, value_parser = parse_cell, allow_hyphen_values = true)]
        cell: ViewCell,
        #[arg(long)]
        samples: Option<u32>,
        #[arg(long)]
        resolution: Option<u32>,
        #[arg(long)]
        json: bool,
    },
    /// Compute the PVS of every cell of a cells.json into a .pvs file.
    #[command(after_help = methods_help())]
    Build {
        #[command(flatten)]
        scene: SceneArg,
        /// A cells.json of viewcells (not needed for a .bsp level with a portal method:
        /// every open leaf is stored).
        #[arg(long)]
        cells: Option<PathBuf>,
        /// The method (listed below); default `volumetric` on a mesh level (walkable
        /// viewcells), `erosion` otherwise.
        #[arg(long)]
        method: Option<String>,
        #[arg(long)]
        resolution: Option<u32>,
        /// ext-proj: run the occlusion sweep.
        #[arg(long)]
        sweep: bool,
        /// ext-proj --sweep: number of sweep planes per direction (default 15, §7.2).
        #[arg(long)]
        planes: Option<u32>,
        /// Any knob of the method by key, repeatable (`--set virtual_occluders=true`; the
        /// keys each method takes are listed below).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        #[arg(short, long)]
        out: PathBuf,
        /// Continue an interrupted build from its journal.
        #[arg(long)]
        resume: bool,
        /// Build only shard I of N (`I/N`, or `auto/N` from JOB_COMPLETION_INDEX / SLURM_ARRAY_TASK_ID).
        #[arg(long)]
        shard: Option<String>,
        /// Mesh levels with `portals`/`portals-fast`: the voxel size of the automatic
        /// cells (scene units; default automatic, see docs/methods/auto-cells.md).
        #[arg(long)]
        smallest_hole: Option<f64>,
        /// Mesh levels with `volumetric`: the viewer's eye above the floor (scene
        /// units; default 1.7, or 3.5 voxels when the voxels are coarser).
        #[arg(long)]
        eye_height: Option<f64>,
        /// Mesh levels with `volumetric`: keep only the viewcells a walker reaches from
        /// this point `X,Y,Z` (repeat for several; docs/methods/volumetric.md).
        #[arg(long = "spawn", value_parser = parse_point, allow_hyphen_values = true)]
        spawn: Vec<[f64; 3]>,
        /// Mesh levels with `volumetric`: viewcells instead of the walkable floors, from
        /// a JSON array of boxes `[{"min": [x, y, z], "max": [x, y, z]}, …]` or a mesh
        /// file (.obj, .gltf, .glb) whose objects' bounding boxes are the volumes (scene
        /// units).
        #[arg(long)]
        view_volumes: Option<PathBuf>,
        /// With a mesh file of `--view-volumes`: only its objects (glTF nodes, OBJ
        /// objects) whose name matches PATTERN (`*` any run, `?` one character).
        #[arg(long, value_name = "PATTERN")]
        view_volume_names: Option<String>,
    },
    /// Merge shard .pvs files into one.
    Merge {
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        #[arg(short, long)]
        out: PathBuf,
    },
    /// PVS of the cell containing a point, or gameplay queries on the cells.
    Query {
        pvs: PathBuf,
        /// The point `X,Y,Z`.
        #[arg(long, value_parser = parse_point, allow_hyphen_values = true,
              required_unless_present_any = ["can_see", "seen_by", "secondary"],
              conflicts_with_all = ["can_see", "seen_by", "secondary"])]
        at: Option<[f64; 3]>,
        /// Whether cell A may see cell B (`A,B`; docs/engines.md states the guarantee).
        #[arg(long, value_parser = parse_cell_pair)]
        can_see: Option<[u32; 2]>,
        /// The cells that may see the point `X,Y,Z`.
        #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
        seen_by: Option<[f64; 3]>,
        /// The secondary PVS of a cell: the union of the PVS of the cells that may see it.
        #[arg(long)]
        secondary: Option<u32>,
        #[arg(long)]
        json: bool,
    },
    /// Recompute ground truth on some cells and report missed/over of a method or a .pvs.
    #[command(after_help = methods_help())]
    Check {
        #[command(flatten)]
        scene: SceneArg,
        /// A .pvs file to check (otherwise --method is run on --cells).
        pvs: Option<PathBuf>,
        /// The method (listed below).
        #[arg(long)]
        method: Option<String>,
        /// A cells.json (with --method), or a number of cells to sample from the .pvs.
        #[arg(long)]
        cells: Option<String>,
        #[arg(long)]
        resolution: Option<u32>,
        /// ext-proj: run the occlusion sweep.
        #[arg(long)]
        sweep: bool,
        /// ext-proj --sweep: number of sweep planes per direction (default 15, §7.2).
        #[arg(long)]
        planes: Option<u32>,
        /// Any knob of the method by key, repeatable (`--set virtual_occluders=true`; the
        /// keys each method takes are listed below).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// A .bsp level with a portal method: compare with the level's own PVS (`vis`)
        /// and the ray oracle (--cells K: K source leaves for the oracle, default 20).
        #[arg(long, value_parser = ["vis"])]
        reference: Option<String>,
        /// Mesh levels with `portals`/`portals-fast`: the voxel size of the automatic
        /// cells (scene units; default automatic, see docs/methods/auto-cells.md).
        #[arg(long)]
        smallest_hole: Option<f64>,
        /// Mesh levels with `volumetric` (the default there): the viewer's eye above the
        /// floor (scene units; default 1.7, or 3.5 voxels when the voxels are coarser).
        #[arg(long)]
        eye_height: Option<f64>,
        /// Mesh levels with `volumetric`: judge only viewcells a walker reaches from this
        /// point `X,Y,Z` (repeatable; as `build`).
        #[arg(long = "spawn", value_parser = parse_point, allow_hyphen_values = true)]
        spawn: Vec<[f64; 3]>,
        /// Mesh levels with `volumetric`: the viewcells from a JSON file of boxes or a
        /// mesh file of volumes (as `build`).
        #[arg(long)]
        view_volumes: Option<PathBuf>,
        /// Of a mesh file of `--view-volumes`: the objects whose name matches (as `build`).
        #[arg(long, value_name = "PATTERN")]
        view_volume_names: Option<String>,
        #[arg(long)]
        json: bool,
    },
    /// Top-down PNG of a scene with a cell's PVS classified against the ground truth
    /// (a .bsp level: its plan with the PVS of the leaf holding --at).
    #[command(after_help = methods_help())]
    Map {
        #[command(flatten)]
        scene: SceneArg,
        #[arg(long, value_parser = parse_cell, allow_hyphen_values = true, required_unless_present = "at")]
        cell: Option<ViewCell>,
        /// BSP levels with `portals`/`portals-fast`: the leaf holding `X,Y,Z`.
        #[arg(long, value_parser = parse_point, allow_hyphen_values = true, conflicts_with = "cell")]
        at: Option<[f64; 3]>,
        /// The method (listed below).
        #[arg(long)]
        method: Option<String>,
        #[arg(long)]
        pvs: Option<PathBuf>,
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Reproduce the papers' experiments; write a Markdown report with plots.
    #[command(after_help = methods_help())]
    Bench {
        #[arg(long, default_value = "quick")]
        suite: String,
        /// Extra real scenes to include.
        #[arg(long)]
        scene: Vec<PathBuf>,
        /// Comma-separated method names (default: all conservative methods; listed below).
        #[arg(long)]
        methods: Option<String>,
        /// Quake levels of the indoor section: `.bsp` files or folders of them, repeatable
        /// (default: `data/quake` when it exists).
        #[arg(long)]
        levels: Vec<PathBuf>,
        /// Run only the level sections (indoor, and meshes with --meshes): no city
        /// experiments.
        #[arg(long)]
        indoor_only: bool,
        /// The mesh section (`volumetric` on walkable viewcells): a small generated level,
        /// plus any mesh levels given (`.obj`, `.gltf`, `.glb`).
        #[arg(long, num_args = 0.., value_name = "LEVEL")]
        meshes: Option<Vec<PathBuf>>,
        /// Mesh section: walkable viewcells per level whose PVS is computed, spread over
        /// the level (default: 64 with --suite quick, all with full; 0: all).
        #[arg(long)]
        mesh_viewcells: Option<usize>,
        #[arg(short, long, default_value = "report")]
        out: PathBuf,
        /// Comma-separated experiments to run (default all): `Fig. 9`, `side by side`,
        /// `Table 1`, `Fig. 12 + sweep`, `scaling`, `from-point`, or a section's levels:
        /// `indoor`, `meshes`.
        #[arg(long)]
        only: Option<String>,
        /// Indoor section: run this reference `vis` (ericw-tools) beside `sightline vis`
        /// on every level, alternating, from the same `.prt` (default: `vis` on `PATH`
        /// when it is ericw-tools').
        #[arg(long, value_name = "PATH")]
        vis_reference: Option<PathBuf>,
        /// Indoor section beside the reference: start both tools from `DIR/LEVEL.prt`
        /// when it exists (default: our own portals, written as PRT1).
        #[arg(long, value_name = "DIR")]
        vis_prt: Option<PathBuf>,
    },
    /// Serve a scene (and optionally a .pvs) to walkthrough clients.
    #[command(after_help = methods_help())]
    Serve {
        #[command(flatten)]
        scene: SceneArg,
        /// A .pvs of the scene to serve (`build` writes one); also `--pvs`.
        pvs: Option<PathBuf>,
        /// The .pvs to serve (same as the positional argument).
        #[arg(long = "pvs", value_name = "PVS", conflicts_with = "pvs")]
        pvs_flag: Option<PathBuf>,
        #[arg(long, default_value = "127.0.0.1:8080")]
        addr: String,
        #[arg(long, default_value_t = 100.0)]
        cell_size: f64,
        /// The method (listed below). A city: the on-line method of its grid cells
        /// (default dual-ray). A level: the method its PVS is built with in memory
        /// before serving (a .bsp: default portals-fast; a mesh level, .obj, .gltf,
        /// .glb: default volumetric on its walkable viewcells, or portals/portals-fast).
        #[arg(long)]
        method: Option<String>,
        /// Eye height above the ground or floor, in scene units (default: 1.7 in a city;
        /// 46 in a BSP level, a Quake player's eye above the floor; in a mesh level the
        /// larger of 1.7 and 2.5 × the smallest hole, so that the eye is in free space).
        #[arg(long, allow_hyphen_values = true)]
        eye_height: Option<f64>,
        /// Mesh levels: the smallest hole of the voxelization, in scene units (as `build`).
        #[arg(long)]
        smallest_hole: Option<f64>,
        /// Require this token (`?token=` or `Authorization: Bearer`).
        #[arg(long)]
        token: Option<String>,
        /// Resolution of the on-line method (its default if not given).
        #[arg(long)]
        resolution: Option<u32>,
        /// Worker threads computing PVS on-line (default: one per core).
        #[arg(long)]
        workers: Option<usize>,
        /// A tileset folder of this scene (`sightline tiles`): served with its PVS-driven
        /// viewer at /tiles/.
        #[arg(long)]
        tiles: Option<PathBuf>,
    },
    /// Export a scene as an OGC 3D Tiles 1.1 tileset (and its tile-level PVS).
    Tiles {
        #[command(flatten)]
        scene: SceneArg,
        /// Output folder (written atomically; replaces a previous tileset).
        #[arg(short, long)]
        out: PathBuf,
        /// Most objects (features) per tile.
        #[arg(long, default_value_t = 16)]
        max_features_per_tile: usize,
        /// A .pvs of this scene: writes the tile-level PVS sidecar `sightline-pvs.json`.
        #[arg(long)]
        pvs: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// From-point occlusion culling along a camera path (docs/culling.md): per frame the objects
    /// that may be visible, with `hzb`, `hom`, `hom-approx` (not conservative) or `cplp`.
    Frames {
        #[command(flatten)]
        scene: SceneArg,
        /// Path file: JSON list of `{"eye": [x,y,z], "dir": [dx,dy,dz], "fov_deg": 60}`.
        #[arg(long, conflicts_with = "walk", required_unless_present = "walk")]
        path: Option<PathBuf>,
        /// Instead of --path: a generated street-level walk of N frames.
        #[arg(long)]
        walk: Option<usize>,
        /// Seed of --walk.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// A .pvs of this scene: each frame is culled within the PVS of the eye's cell
        /// (two-level culling).
        #[arg(long)]
        pvs: Option<PathBuf>,
        #[arg(long, default_value = "hzb")]
        method: String,
        /// Frame size `WIDTHxHEIGHT` in pixels.
        #[arg(long, default_value = "1920x1080")]
        size: String,
        /// Occluders: the objects' inner prisms (`prisms`), or also the surfaces of mesh
        /// objects, each triangle or convex face hiding what is entirely behind it
        /// (`surfaces`: a BSP level's world faces bounding its solid, a mesh level's
        /// opaque triangles); `auto` takes `surfaces` when the scene has meshes.
        #[arg(long, value_enum, default_value_t = OccluderArg::Auto)]
        occluders: OccluderArg,
        /// --walk on a scene without blocks (a BSP or mesh level): eyes this high above
        /// random floor triangles (scene units; a Quake player's eye is ~46 above the floor).
        #[arg(long, default_value_t = 1.7, allow_hyphen_values = true)]
        eye_height: f64,
        #[arg(long)]
        json: bool,
    },
    /// Compute a Quake level's leaf PVS and write it into the level's visibility lump
    /// (as Quake's `vis` does), keeping the original as LEVEL.bsp.orig.
    Vis(crate::commands::vis::VisArgs),
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum OccluderArg {
    Auto,
    Prisms,
    Surfaces,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum GenerateKind {
    City,
    Forest,
    Metropolis,
}

//! One door for every scene kind: [`World`] opens a city, a BSP level or a mesh level
//! with its cell layout — viewcell boxes given by the user, a BSP's open leaves, a mesh
//! level's automatic cells and walkable viewcells — and answers the questions every
//! face (the CLI, the server, Python) asks, whatever the kind: the PVS at a point or of
//! a box, the `.pvs` bytes of a whole level, its cells, and its PVS judged against the
//! ground truth ([`judge`]). The kind comes from [`kind_of`]; which method applies to it
//! from the registry ([`sightline_core::Method::works_on`], resolved once by
//! [`World::resolve`]). The architecture: README's "Architecture", `docs/families.md`.
//!
//! ```no_run
//! use sightline_world::{OpenOptions, World};
//! let world = World::open("data/quake/dm1.bsp".as_ref(), &OpenOptions::default())?;
//! let m = world.resolve(Some("portals-fast"))?;
//! let answer = world.pvs_at(m, [200.0, 1000.0, 50.0])?;
//! println!("{} of {} faces", answer.visible.len(), answer.objects);
//! # anyhow::Ok(())
//! ```

pub mod bsp;
pub mod judge;
mod kind;
pub mod mesh;
mod method;

pub use bsp::BspInfo;
pub use judge::{Evidence, Judgement, Miss};
pub use kind::{kind_of, kind_word, kind_words};
pub use mesh::{
    cut_level, default_eye_height, free_space, sources_from_params, spread, walkable_viewcells,
    CutLevel, EncodedLevel, Standing, VIEWCELL_WIDTH,
};
pub use method::{default_method, on_level_cells, portal_mode, resolve, serving_method};
pub use sightline_core::SceneKind;

use anyhow::Context;
use serde::Serialize;
use sightline_autocells::AutoCells;
use sightline_core::check::{check_cells, TruthOptions};
use sightline_core::{Method, MethodError, MethodOptions, VisibilityMethod};
use sightline_geom::ViewCell;
use sightline_portals::{PortalMethod, Portals};
use sightline_scene::clusters::Clustered;
use sightline_scene::import::bsp::BspLevel;
use sightline_scene::import::ImportOptions;
use sightline_scene::Scene;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// How to open a scene: the importer's options, and for a mesh level the smallest hole
/// its voxels resolve and where viewers stand.
#[derive(Clone, Debug, Default)]
pub struct OpenOptions {
    pub import: ImportOptions,
    /// `--smallest-hole` (mesh levels; `None`: the cutter's default).
    pub smallest_hole: Option<f64>,
    /// `--eye-height`, `--spawn`, `--view-volumes` (mesh levels, `volumetric`).
    pub standing: Standing,
}

/// A scene of any kind, loaded, with what its cell layout needs.
pub struct World {
    path: PathBuf,
    kind: SceneKind,
    opts: OpenOptions,
    /// The objects as the importer reads them: a city's, a BSP's world faces, a mesh
    /// level's source objects (before clustering).
    scene: Arc<Scene>,
    bsp: Option<BspLevel>,
}

/// The PVS of one cell, as `pvs` reports it (`--json` prints it as it is).
#[derive(Clone, Debug, Serialize)]
pub struct PvsAnswer {
    pub method: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 3]>,
    /// The box asked for, or the automatic cell holding the point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cell: Option<ViewCell>,
    /// BSP levels: the leaf holding the point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leaf: Option<u32>,
    /// Mesh levels: the automatic cell holding the point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub index: Option<u32>,
    /// Objects the ids count: a city's objects, a BSP's faces, a mesh level's clusters.
    pub objects: usize,
    /// Mesh levels: the source objects the clusters come from.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sources: Option<usize>,
    pub visible: Vec<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visible_leaves: Option<Vec<u32>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visible_sources: Option<Vec<u32>>,
    pub seconds: f64,
    /// BSP levels: the leaves a leaf PVS counts (`visleafs`).
    #[serde(skip)]
    pub visleafs: Option<u32>,
}

/// What the objects of a [`PvsAnswer`] are, in words ("faces", "clusters", "objects").
impl PvsAnswer {
    pub fn unit(&self) -> &'static str {
        if self.sources.is_some() {
            "clusters"
        } else if self.visleafs.is_some() {
            "faces"
        } else {
            "objects"
        }
    }
}

/// The `.pvs` of a whole level, with what `build` and `serve` say of it.
pub struct Encoded {
    pub method: Method,
    pub bytes: Vec<u8>,
    /// Cells stored (leaves, automatic cells, walkable viewcells and free space).
    pub cells: usize,
    /// The objects the ids index: a BSP's faces, a mesh level's clusters.
    pub scene: Scene,
    /// Mesh levels: the cut, its counts and warnings.
    pub mesh: Option<MeshFacts>,
}

/// What a mesh level's build reports.
#[derive(Clone, Debug)]
pub struct MeshFacts {
    /// Automatic cells and portals of the cut.
    pub auto_cells: usize,
    pub portals: usize,
    pub clusters: usize,
    pub sources: usize,
    pub smallest_hole: f64,
    /// Walkable viewcells stored first (`volumetric`), else 0.
    pub viewcells: usize,
    pub warnings: Vec<String>,
    /// The clustering (the `.pvs`'s ids).
    pub clustered: Arc<Clustered>,
}

impl World {
    /// Open the scene at `path`: its kind from the extension ([`kind_of`]), then its
    /// objects (a BSP level also keeps its tree).
    pub fn open(path: &Path, opts: &OpenOptions) -> anyhow::Result<World> {
        let kind = kind_of(path);
        let cannot = || format!("cannot load {}", path.display());
        let (scene, bsp) = match kind {
            SceneKind::Bsp => {
                let level = sightline_scene::import::bsp::load_bsp(path).with_context(cannot)?;
                (level.to_scene(), Some(level))
            }
            _ => (
                sightline_scene::import::load(path, &opts.import).with_context(cannot)?,
                None,
            ),
        };
        Ok(World {
            path: path.to_path_buf(),
            kind,
            opts: opts.clone(),
            scene: Arc::new(scene),
            bsp,
        })
    }

    pub fn kind(&self) -> SceneKind {
        self.kind
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The objects as the importer reads them (a mesh level's before clustering).
    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    /// A BSP level's tree.
    pub fn bsp(&self) -> Option<&BspLevel> {
        self.bsp.as_ref()
    }

    pub fn options(&self) -> &OpenOptions {
        &self.opts
    }

    /// The method used when none is named ([`default_method`]).
    pub fn default_method(&self) -> Method {
        default_method(self.kind)
    }

    /// `name` (or the default) as a method that works on this scene ([`resolve`]).
    pub fn resolve(&self, name: Option<&str>) -> anyhow::Result<Method> {
        resolve(self.kind, &self.path, name)
    }

    fn ensure_mesh(&self) -> anyhow::Result<()> {
        anyhow::ensure!(
            self.kind == SceneKind::Mesh,
            "{} is not a mesh level (.obj, .gltf, .glb)",
            self.path.display()
        );
        Ok(())
    }

    /// A mesh level clustered and cut into automatic cells with their PVS (`full`: the
    /// portal flow, else the flood), at the smallest hole of the options.
    pub fn cut(&self, full: bool) -> anyhow::Result<CutLevel> {
        self.ensure_mesh()?;
        cut_level(
            &self.scene,
            &self.path.display().to_string(),
            self.opts.smallest_hole,
            full,
        )
    }

    /// The cutting options of this mesh level at `smallest_hole` (the clusters depend
    /// on them).
    pub fn cluster_options(
        &self,
        smallest_hole: Option<f64>,
    ) -> anyhow::Result<sightline_autocells::Options> {
        cluster_options(smallest_hole)
    }

    /// The clusters of this mesh level with `opts` (the ids of its `.pvs`).
    pub fn clusters(&self, opts: &sightline_autocells::Options) -> Clustered {
        mesh::cluster_level(&self.scene, opts)
    }

    /// The clustered scene a `.pvs` of this mesh level was built on: the level clustered
    /// as `build` clusters it, with the smallest hole the file records.
    pub fn clustered_for(&self, file: &sightline_pvs::PvsFile) -> anyhow::Result<Clustered> {
        self.ensure_mesh()?;
        let opts = mesh::options(mesh::smallest_hole_of(file), false)?;
        Ok(mesh::cluster_level(&self.scene, &opts))
    }

    /// A BSP level's `info_player_start`, if it has one.
    pub fn player_start(&self) -> Option<[f64; 3]> {
        self.bsp.as_ref()?;
        let bytes = std::fs::read(&self.path).ok()?;
        sightline_scene::import::bsp::player_start(&bytes)
    }

    /// `info`'s extras: a BSP level's leaf and portal counts.
    pub fn bsp_info(&self) -> anyhow::Result<Option<BspInfo>> {
        self.bsp.as_ref().map(bsp::info).transpose()
    }

    /// The PVS of the cell holding `p` (a BSP leaf, a mesh level's automatic cell) with
    /// a portal method.
    pub fn pvs_at(&self, m: Method, p: [f64; 3]) -> anyhow::Result<PvsAnswer> {
        let Some(mode) = portal_mode(m).filter(|_| m.works_on(self.kind)) else {
            anyhow::bail!(
                "--at answers for the leaf holding a point: it needs a .bsp or mesh level (.obj, .gltf, .glb) and --method portals or portals-fast"
            );
        };
        let t = Instant::now();
        if let Some(level) = &self.bsp {
            let pm = PortalMethod::new(bsp::portals(level)?, mode);
            let leaf = level.point_leaf(p);
            anyhow::ensure!(
                level.is_view_leaf(leaf),
                "point {},{},{} is not in open space (leaf {leaf} is solid, sky or outside the level)",
                p[0],
                p[1],
                p[2]
            );
            let pvs = pm.leaf_pvs(leaf);
            return Ok(PvsAnswer {
                method: m.name(),
                at: Some(p),
                cell: None,
                leaf: Some(leaf),
                index: None,
                objects: level.faces.len(),
                sources: None,
                visible: pvs.faces,
                visible_leaves: Some(pvs.leaves),
                visible_sources: None,
                seconds: t.elapsed().as_secs_f64(),
                visleafs: Some(level.visleafs),
            });
        }
        let cut = self.cut(m == Method::Portals)?;
        let auto = &cut.auto;
        let c = auto.locate(p).with_context(|| {
            format!(
                "point {},{},{} is not in the level's free space (solid or outside)",
                p[0], p[1], p[2]
            )
        })?;
        let visible = auto.pvs(c as usize);
        Ok(self.mesh_answer(
            &cut,
            m,
            Some(p),
            auto.cell_box(c as usize),
            Some(c),
            visible,
            t,
        ))
    }

    #[allow(clippy::too_many_arguments)]
    fn mesh_answer(
        &self,
        cut: &CutLevel,
        m: Method,
        at: Option<[f64; 3]>,
        cell: ViewCell,
        index: Option<u32>,
        visible: Vec<u32>,
        t: Instant,
    ) -> PvsAnswer {
        PvsAnswer {
            method: m.name(),
            at,
            cell: Some(cell),
            leaf: None,
            index,
            objects: cut.auto.objects,
            sources: Some(cut.clustered.source_names.len()),
            visible_sources: Some(cut.clustered.sources_of(&visible)),
            visible,
            visible_leaves: None,
            seconds: t.elapsed().as_secs_f64(),
            visleafs: None,
        }
    }

    /// The method `m` prepared on this scene, answering for boxes: a portal method on
    /// the level's cells (the union over the cells a box meets), any other on the
    /// objects (`opts` its knobs).
    pub fn method(
        &self,
        m: Method,
        opts: &MethodOptions,
    ) -> anyhow::Result<Box<dyn VisibilityMethod>> {
        if let (Some(mode), Some(level)) = (portal_mode(m), &self.bsp) {
            return Ok(Box::new(PortalMethod::new(bsp::portals(level)?, mode)));
        }
        if let Some(mode) = portal_mode(m).filter(|_| self.kind == SceneKind::Mesh) {
            let cut = self.cut(mode == sightline_portals::Mode::Full)?;
            return Ok(Box::new(CellsMethod {
                method: m,
                auto: cut.auto,
            }));
        }
        anyhow::ensure!(
            m != Method::Volumetric,
            "volumetric answers on the walkable viewcells of a build: build {} -o L.pvs, then query L.pvs --at X,Y,Z",
            self.path.display()
        );
        Ok(sightline_methods::create(
            m.name(),
            self.scene.clone(),
            opts,
        )?)
    }

    /// The PVS of the box `cell` with `m`: on a level with a portal method the union of
    /// the PVS of its cells that meet the box; else the method on the objects.
    pub fn pvs_of(
        &self,
        m: Method,
        cell: &ViewCell,
        opts: &MethodOptions,
    ) -> anyhow::Result<PvsAnswer> {
        let t0 = Instant::now();
        if self.kind == SceneKind::Mesh && portal_mode(m).is_some() {
            let cut = self.cut(m == Method::Portals)?;
            let visible = union_over_cells(&cut.auto, cell);
            return Ok(self.mesh_answer(&cut, m, None, *cell, None, visible, t0));
        }
        let prepared = self.method(m, opts)?;
        // A level's portals are part of the answer's time, a city method's preparation
        // is not (as `pvs` always timed them).
        let t = if self.bsp.is_some() {
            t0
        } else {
            Instant::now()
        };
        let visible = prepared.pvs(cell)?;
        Ok(PvsAnswer {
            method: prepared.name(),
            at: None,
            cell: Some(*cell),
            leaf: None,
            index: None,
            objects: self.scene.objects.len(),
            sources: None,
            visible,
            visible_leaves: None,
            visible_sources: None,
            seconds: t.elapsed().as_secs_f64(),
            visleafs: self.bsp.as_ref().map(|l| l.visleafs),
        })
    }

    /// An error unless `m` works on this scene's own cells (`verb`: "is built on",
    /// "judges").
    fn ensure_level_method(&self, m: Method, verb: &str) -> anyhow::Result<()> {
        anyhow::ensure!(
            on_level_cells(m) && m.works_on(self.kind),
            "{} {verb} the cells of a level; {} is {}",
            m.name(),
            self.path.display(),
            kind_word(self.kind)
        );
        Ok(())
    }

    /// The `.pvs` of the whole level with `m`: every open leaf of a BSP level, every
    /// automatic cell of a mesh level (`portals`, `portals-fast`), or its walkable
    /// viewcells then its automatic cells (`volumetric`, with the options' standing).
    pub fn encode(&self, m: Method) -> anyhow::Result<Encoded> {
        self.ensure_level_method(m, "is built on")?;
        if let Some(level) = &self.bsp {
            let mode = portal_mode(m).context("a BSP level is built with a portal method")?;
            let (bytes, cells) = bsp::encode(level, mode)
                .with_context(|| format!("cannot build the PVS of {}", self.path.display()))?;
            return Ok(Encoded {
                method: m,
                bytes,
                cells,
                scene: level.to_scene(),
                mesh: None,
            });
        }
        let cut = self.cut(m == Method::Portals)?;
        let enc = if m == Method::Volumetric {
            mesh::encode_volumetric(cut, &self.opts.standing)?
        } else {
            mesh::encode_portals(cut, m)?
        };
        let EncodedLevel {
            level,
            viewcells,
            bytes,
        } = enc;
        let r = &level.auto.report;
        let facts = MeshFacts {
            auto_cells: r.cells,
            portals: r.portals,
            clusters: level.auto.objects,
            sources: level.clustered.source_names.len(),
            smallest_hole: r.smallest_hole,
            viewcells,
            warnings: level.warnings,
            clustered: Arc::new(level.clustered),
        };
        Ok(Encoded {
            method: m,
            bytes,
            cells: viewcells + r.cells,
            scene: facts.clustered.scene.clone(),
            mesh: Some(facts),
        })
    }

    /// Judge `m` on the level's own cells: `k` source leaves of a BSP level against its
    /// `vis` and the ray oracle (16 segments per pair we call hidden, 256 for pairs the
    /// reference has); `k` automatic cells (`portals`, `portals-fast`) or walkable
    /// viewcells (`volumetric`) of a mesh level against the item-buffer truth sampled in
    /// their free voxels. Also returns the cut of a mesh level.
    pub fn judge(&self, m: Method, k: usize) -> anyhow::Result<(Judgement, Option<JudgedLevel>)> {
        self.ensure_level_method(m, "judges")?;
        if let Some(level) = &self.bsp {
            let mode = portal_mode(m).context("a BSP level is judged with a portal method")?;
            let portals: Portals = bsp::portals(level)?;
            let r = sightline_portals::reference::compare_with_reference(&portals, mode, k, 16);
            return Ok((Judgement::of_leaves(r), None));
        }
        use rayon::prelude::*;
        let t = Instant::now();
        let cut = self.cut(m == Method::Portals)?;
        let truth = TruthOptions::default();
        if m != Method::Volumetric {
            let seconds_pvs = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let judged = cut.auto.judge(&cut.clustered.scene, k, &truth);
            let auto = &cut.auto;
            let j = Judgement::of_cells(
                m.name(),
                judged,
                (0..auto.len()).map(|c| auto.pvs(c).len()),
                auto.objects,
            );
            let facts = JudgedLevel {
                cells: auto.len(),
                clusters: auto.objects,
                eye_height: None,
                seconds_pvs,
                seconds_truth: t.elapsed().as_secs_f64(),
                cut,
            };
            return Ok((j, Some(facts)));
        }
        let (eye, viewcells) = walkable_viewcells(&cut.auto, &self.opts.standing)?;
        anyhow::ensure!(
            !viewcells.is_empty(),
            "no walkable floor in {} (no upward surface with room for the eye at {eye})",
            self.path.display()
        );
        let picked = spread(&viewcells, k);
        let auto = &cut.auto;
        let vol = auto.volumetric();
        let pvs: Vec<Vec<u32>> = picked
            .par_iter()
            .map(|b| auto.viewcell_pvs(&vol, b))
            .collect();
        let seconds_pvs = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let judged = auto.judge_boxes(
            &cut.clustered.scene,
            &picked,
            |c| pvs[c].clone(),
            picked.len(),
            &truth,
        );
        let j = Judgement::of_cells(m.name(), judged, pvs.iter().map(Vec::len), auto.objects);
        let facts = JudgedLevel {
            cells: viewcells.len(),
            clusters: auto.objects,
            eye_height: Some(eye),
            seconds_pvs,
            seconds_truth: t.elapsed().as_secs_f64(),
            cut,
        };
        Ok((j, Some(facts)))
    }

    /// Judge a prepared method (or a stored `.pvs`) on viewcell boxes of this scene
    /// against the item-buffer truth; `progress` is called once per judged cell.
    pub fn judge_boxes(
        &self,
        m: &dyn VisibilityMethod,
        cells: &[ViewCell],
        progress: &(dyn Fn() + Sync),
    ) -> anyhow::Result<Judgement> {
        let report = check_cells(&self.scene, m, cells, &TruthOptions::default(), progress)?;
        Ok(Judgement::of_boxes(report, m.is_conservative()))
    }
}

/// The cutting options of a mesh level at `smallest_hole`, as `build` clusters it
/// (checked: a positive number).
pub fn cluster_options(smallest_hole: Option<f64>) -> anyhow::Result<sightline_autocells::Options> {
    mesh::options(smallest_hole, false)
}

/// What judging a mesh level's cells measured besides the [`Judgement`].
pub struct JudgedLevel {
    /// Cells of the kind judged (automatic cells, or walkable viewcells).
    pub cells: usize,
    pub clusters: usize,
    /// `volumetric`: the eye height of the walkable viewcells.
    pub eye_height: Option<f64>,
    pub seconds_pvs: f64,
    pub seconds_truth: f64,
    pub cut: CutLevel,
}

/// The union of the PVS of the automatic cells whose box meets `cell`, sorted.
fn union_over_cells(auto: &AutoCells, cell: &ViewCell) -> Vec<u32> {
    let mut v: Vec<u32> = (0..auto.len())
        .filter(|&c| {
            let b = auto.cell_box(c);
            (0..3).all(|k| b.min[k] <= cell.max[k] && b.max[k] >= cell.min[k])
        })
        .flat_map(|c| auto.pvs(c))
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// A mesh level's automatic cells as a [`VisibilityMethod`] (`portals`,
/// `portals-fast`): a box is answered by the union of the cells it meets, as
/// `sightline_portals::PortalMethod` answers a BSP level's leaves.
pub struct CellsMethod {
    method: Method,
    auto: AutoCells,
}

impl CellsMethod {
    /// `auto`'s cells answering as `method` (a portal method).
    pub fn new(method: Method, auto: AutoCells) -> CellsMethod {
        CellsMethod { method, auto }
    }

    pub fn cells(&self) -> &AutoCells {
        &self.auto
    }
}

impl VisibilityMethod for CellsMethod {
    fn name(&self) -> &'static str {
        self.method.name()
    }

    fn params(&self) -> Vec<(String, String)> {
        vec![(
            "smallest_hole".to_string(),
            self.auto.report.smallest_hole.to_string(),
        )]
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        Ok(union_over_cells(&self.auto, cell))
    }
}

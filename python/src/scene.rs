//! `NativeScene`: a loaded scene with its prepared methods and ground-truth renderer
//! cached, so repeated calls from Python prepare nothing twice.

use crate::errors::{detached, err, method_err, Kind};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use rayon::prelude::*;
use sightline_core::check::{TruthOptions, TruthScene};
use sightline_geom::ViewCell;
use sightline_methods::{MethodOptions, VisibilityMethod};
use sightline_portals::{Mode, PortalMethod, Portals};
use sightline_scene::import::bsp::BspLevel;
use sightline_scene::import::{Crs, ImportOptions};
use sightline_scene::{cells, Scene};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

/// Largest accepted ground-truth cube-face resolution and sample count (as the CLI's).
const MAX_TRUTH_RESOLUTION: u32 = 8192;
const MAX_TRUTH_SAMPLES: u32 = 100_000;

/// The options that identify a prepared method.
/// A method and its settings (every field of `MethodOptions`, knobs included, as JSON).
type MethodKey = (String, String);

#[pyclass(module = "sightline._native", frozen, name = "NativeScene")]
pub struct NativeScene {
    pub scene: Arc<Scene>,
    /// What `info()["scene"]` reports: the path, or the name given to a GeoDataFrame.
    name: String,
    methods: Mutex<HashMap<MethodKey, Arc<dyn VisibilityMethod>>>,
    truth: OnceLock<Arc<TruthScene>>,
    /// Occluders and occludees for from-point culling, prepared on first use.
    culling: OnceLock<Arc<sightline_culling::CullScene>>,
    /// A Quake level (`.bsp`): its tree, for the portal methods.
    level: Option<Arc<BspLevel>>,
    /// `portals` and `portals-fast` prepared on the level, on first use.
    portal_methods: Mutex<HashMap<&'static str, Arc<PortalMethod>>>,
}

/// The portal mode of a method name, if it is a portal method.
fn portal_mode(method: &str) -> Option<Mode> {
    match method.parse::<sightline_methods::Method>() {
        Ok(sightline_methods::Method::Portals) => Some(Mode::Full),
        Ok(sightline_methods::Method::PortalsFast) => Some(Mode::Fast),
        _ => None,
    }
}

fn crs(arg: Option<&str>) -> PyResult<Crs> {
    match arg {
        None | Some("auto") => Ok(Crs::Auto),
        Some("projected") => Ok(Crs::Projected),
        Some("wgs84") => Ok(Crs::Wgs84),
        Some(other) => Err(err(
            Kind::Scene,
            format!("crs must be 'auto', 'projected' or 'wgs84', got '{other}'"),
        )),
    }
}

/// Method options with the command line's checks: the sweep options belong to
/// `ext-proj` only and are refused for any other method rather than silently ignored.
pub fn method_options(
    method: &str,
    resolution: Option<u32>,
    sweep: bool,
    planes: Option<u32>,
    knobs: Vec<(String, String)>,
) -> PyResult<MethodOptions> {
    if !sightline_methods::METHOD_NAMES.contains(&method) {
        return Err(method_err(sightline_methods::MethodError::Unknown(
            method.to_string(),
        )));
    }
    if sweep && method != "ext-proj" {
        return Err(err(
            Kind::Method,
            format!("sweep only applies to method ext-proj (got '{method}')"),
        ));
    }
    if let Some(k) = planes {
        if !sweep {
            return Err(err(
                Kind::Method,
                "planes sets the number of sweep planes: it needs sweep=True",
            ));
        }
        if !(1..=256).contains(&k) {
            return Err(err(
                Kind::Method,
                format!("planes must be between 1 and 256, got {k}"),
            ));
        }
    }
    if resolution == Some(0) {
        return Err(err(
            Kind::Method,
            "resolution must be a positive number of pixels",
        ));
    }
    let opts = MethodOptions {
        resolution_px: resolution,
        sweep,
        planes,
        set: knobs,
        ..Default::default()
    };
    // The registry validates every knob (by key, as `--set key=value`).
    let m: sightline_methods::Method = method.parse().map_err(method_err)?;
    m.options(&opts).map_err(method_err)?;
    Ok(opts)
}

/// The registry as JSON: every method with its family, paper, guarantee and knobs.
#[pyfunction]
pub fn methods_json() -> String {
    let list: Vec<serde_json::Value> = sightline_methods::Method::ALL
        .iter()
        .map(|m| {
            serde_json::json!({
                "name": m.name(),
                "family": format!("{:?}", m.family()).to_lowercase(),
                "paper": m.paper(),
                "summary": m.summary(),
                "conservative": m.is_conservative(),
                "knobs": m.knobs().iter().map(|k| serde_json::json!({"key": k.key, "help": k.help})).collect::<Vec<_>>(),
            })
        })
        .collect();
    serde_json::Value::Array(list).to_string()
}

/// A viewcell from six numbers, validated (finite, min <= max).
pub fn cell(a: [f64; 6]) -> PyResult<ViewCell> {
    ViewCell::from_array(a).map_err(|e| err(Kind::Cell, format!("bad viewcell {a:?}: {e}")))
}

/// Cells from the little-endian bytes of an N×6 `f64` array.
pub fn cells_from_bytes(bytes: &[u8]) -> PyResult<Vec<ViewCell>> {
    const CELL_BYTES: usize = 6 * 8;
    if !bytes.len().is_multiple_of(CELL_BYTES) {
        return Err(err(Kind::Cell, "cells must be an N×6 array of numbers"));
    }
    bytes
        .chunks_exact(CELL_BYTES)
        .enumerate()
        .map(|(k, c)| {
            let mut a = [0.0; 6];
            for (v, b) in a.iter_mut().zip(c.chunks_exact(8)) {
                let mut le = [0u8; 8];
                le.copy_from_slice(b);
                *v = f64::from_le_bytes(le);
            }
            ViewCell::from_array(a).map_err(|e| err(Kind::Cell, format!("cell {k} {a:?}: {e}")))
        })
        .collect()
}

pub fn cells_to_bytes(cells: &[ViewCell]) -> Vec<u8> {
    cells
        .iter()
        .flat_map(|c| c.to_array())
        .flat_map(f64::to_le_bytes)
        .collect()
}

pub fn ids_to_bytes(ids: &[u32]) -> Vec<u8> {
    ids.iter().flat_map(|i| i.to_le_bytes()).collect()
}

/// A pool of `threads` workers, kept for reuse (`None`: rayon's global pool).
pub fn pool(threads: Option<usize>) -> PyResult<Option<Arc<rayon::ThreadPool>>> {
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> = OnceLock::new();
    let Some(n) = threads else { return Ok(None) };
    if n == 0 {
        return Err(err(Kind::Method, "threads must be at least 1"));
    }
    let mut pools = POOLS
        .get_or_init(Default::default)
        .lock()
        .map_err(|_| err(Kind::Method, "thread pool registry poisoned"))?;
    if let Some(p) = pools.get(&n) {
        return Ok(Some(p.clone()));
    }
    let p = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| err(Kind::Method, format!("cannot start {n} threads: {e}")))?,
    );
    pools.insert(n, p.clone());
    Ok(Some(p))
}

/// Run `f` on `pool`, or on the global pool.
pub fn on_pool<T: Send>(pool: Option<&rayon::ThreadPool>, f: impl FnOnce() -> T + Send) -> T {
    match pool {
        Some(p) => p.install(f),
        None => f(),
    }
}

impl NativeScene {
    fn new(scene: Scene, name: String) -> Self {
        NativeScene {
            scene: Arc::new(scene),
            name,
            methods: Mutex::new(HashMap::new()),
            truth: OnceLock::new(),
            culling: OnceLock::new(),
            level: None,
            portal_methods: Mutex::new(HashMap::new()),
        }
    }

    /// `portals`/`portals-fast` on this scene's level, prepared on first use; an error
    /// when the scene is not a BSP level. Call with the GIL released.
    fn portal_method(&self, mode: Mode) -> PyResult<Arc<PortalMethod>> {
        let name = match mode {
            Mode::Full => sightline_methods::Method::Portals.name(),
            Mode::Fast => sightline_methods::Method::PortalsFast.name(),
        };
        let Some(level) = &self.level else {
            return Err(err(
                Kind::Method,
                format!(
                    "{name} works on BSP levels (.bsp); {} is not one",
                    self.name
                ),
            ));
        };
        let poisoned = || err(Kind::Method, "method cache poisoned");
        if let Some(m) = self
            .portal_methods
            .lock()
            .map_err(|_| poisoned())?
            .get(name)
        {
            return Ok(m.clone());
        }
        let portals =
            Portals::build(level).map_err(|e| err(Kind::Scene, format!("{}: {e}", self.name)))?;
        let m = Arc::new(PortalMethod::new(portals, mode));
        let mut cache = self.portal_methods.lock().map_err(|_| poisoned())?;
        Ok(cache.entry(name).or_insert(m).clone())
    }

    /// The method prepared for this scene with `opts`, prepared on first use. Call with
    /// the GIL released: preparing can take seconds.
    pub fn method(&self, name: &str, opts: &MethodOptions) -> PyResult<Arc<dyn VisibilityMethod>> {
        if let Some(mode) = portal_mode(name) {
            let m: Arc<dyn VisibilityMethod> = self.portal_method(mode)?;
            return Ok(m);
        }
        let key = (
            name.to_string(),
            serde_json::to_string(opts).map_err(|e| err(Kind::Method, e.to_string()))?,
        );
        let poisoned = || err(Kind::Method, "method cache poisoned");
        if let Some(m) = self.methods.lock().map_err(|_| poisoned())?.get(&key) {
            return Ok(m.clone());
        }
        // Prepared outside the lock so that other methods stay usable meanwhile; two
        // threads racing for the same key both prepare and one result is kept.
        let m: Arc<dyn VisibilityMethod> = Arc::from(
            sightline_methods::create(name, self.scene.clone(), opts).map_err(method_err)?,
        );
        let mut cache = self.methods.lock().map_err(|_| poisoned())?;
        Ok(cache.entry(key).or_insert(m).clone())
    }

    pub fn truth_scene(&self) -> Arc<TruthScene> {
        self.truth
            .get_or_init(|| Arc::new(TruthScene::new(&self.scene)))
            .clone()
    }

    pub fn name(&self) -> &str {
        &self.name
    }
}

#[pymethods]
impl NativeScene {
    /// Load a scene file (format chosen by extension, as the CLI).
    #[staticmethod]
    #[pyo3(signature = (path, crs_name=None, strict=false))]
    fn load(py: Python<'_>, path: PathBuf, crs_name: Option<&str>, strict: bool) -> PyResult<Self> {
        let opts = ImportOptions {
            crs: crs(crs_name)?,
            strict,
        };
        let is_bsp = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("bsp"));
        let cannot = |e: &dyn std::fmt::Display| {
            err(Kind::Scene, format!("cannot load {}: {e}", path.display()))
        };
        if is_bsp {
            // A Quake level: the faces are the objects, the tree is kept for the
            // portal methods.
            let level = detached(py, || {
                sightline_scene::import::bsp::load_bsp(&path).map_err(|e| cannot(&e))
            })?;
            let mut s = NativeScene::new(level.to_scene(), path.display().to_string());
            s.level = Some(Arc::new(level));
            return Ok(s);
        }
        let scene = detached(py, || {
            sightline_scene::import::load(&path, &opts).map_err(|e| cannot(&e))
        })?;
        Ok(NativeScene::new(scene, path.display().to_string()))
    }

    /// Import GeoJSON text (the `.geojson` importer, every rule included).
    #[staticmethod]
    #[pyo3(signature = (text, name, crs_name=None, strict=false))]
    fn from_geojson(
        py: Python<'_>,
        text: &str,
        name: String,
        crs_name: Option<&str>,
        strict: bool,
    ) -> PyResult<Self> {
        let opts = ImportOptions {
            crs: crs(crs_name)?,
            strict,
        };
        let scene = detached(py, || {
            sightline_scene::import::geojson::parse(text.as_bytes(), &opts)
                .map_err(|e| err(Kind::Scene, format!("cannot load {name}: {e}")))
        })?;
        Ok(NativeScene::new(scene, name))
    }

    fn __len__(&self) -> usize {
        self.scene.objects.len()
    }

    #[getter]
    fn fingerprint(&self) -> String {
        format!("{:016x}", self.scene.fingerprint())
    }

    #[getter]
    fn source(&self) -> &str {
        &self.name
    }

    /// The `sightline info --json` report, as JSON text; a BSP level adds `bsp` (leaves,
    /// visleafs, open leaves, portals) as the CLI's.
    fn info_json(&self, py: Python<'_>) -> PyResult<String> {
        let mut v = serde_json::to_value(self.scene.info(self.name.clone()))
            .map_err(|e| err(Kind::Scene, e))?;
        if let Some(level) = &self.level {
            let portals = detached(py, || self.portal_method(Mode::Fast))?
                .portals()
                .portals()
                .len();
            let bsp = serde_json::json!({
                "leaves": level.leaves.len(),
                "visleafs": level.visleafs,
                "open_leaves": (1..=level.visleafs).filter(|&l| level.is_view_leaf(l)).count(),
                "portals": portals,
            });
            if let Some(o) = v.as_object_mut() {
                o.insert("bsp".into(), bsp);
            }
        }
        serde_json::to_string(&v).map_err(|e| err(Kind::Scene, e))
    }

    /// BSP levels, `portals`/`portals-fast`: the PVS of the leaf holding `point`, as
    /// `sightline pvs LEVEL.bsp --at X,Y,Z --json` (JSON text: `leaf`, `visible` face
    /// ids, `visible_leaves` leaf numbers).
    fn pvs_at_json(&self, py: Python<'_>, point: [f64; 3], method: &str) -> PyResult<String> {
        let Some(mode) = portal_mode(method) else {
            return Err(err(
                Kind::Method,
                format!(
                    "pvs at a point needs a portal method (portals, portals-fast), got '{method}'"
                ),
            ));
        };
        if point.iter().any(|c| !c.is_finite()) {
            return Err(err(Kind::Cell, format!("point {point:?} is not finite")));
        }
        let (leaf, pvs) = detached(py, || {
            let m = self.portal_method(mode)?;
            let level = m.portals().level();
            let leaf = level.point_leaf(point);
            if !level.is_view_leaf(leaf) {
                return Err(err(
                    Kind::Cell,
                    format!(
                        "point {},{},{} is not in open space (leaf {leaf} is solid, sky or outside the level)",
                        point[0], point[1], point[2]
                    ),
                ));
            }
            Ok((leaf, m.leaf_pvs(leaf)))
        })?;
        let v = serde_json::json!({
            "method": method,
            "at": point,
            "leaf": leaf,
            "objects": self.scene.objects.len(),
            "visible": pvs.faces,
            "visible_leaves": pvs.leaves,
        });
        serde_json::to_string(&v).map_err(|e| err(Kind::Scene, e))
    }

    /// The viewcell grid (`sightline cells`) as little-endian `f64` bytes, 6 per cell.
    fn cells<'py>(
        &self,
        py: Python<'py>,
        size: f64,
        z0: f64,
        z1: f64,
    ) -> PyResult<Bound<'py, PyBytes>> {
        if !(size.is_finite() && size > 0.0) {
            return Err(err(
                Kind::Cell,
                format!("size must be a positive number of metres, got {size}"),
            ));
        }
        if !(z0.is_finite() && z1.is_finite() && 0.0 <= z0 && z0 <= z1) {
            return Err(err(
                Kind::Cell,
                format!("z must satisfy 0 <= z0 <= z1 (finite), got {z0}:{z1}"),
            ));
        }
        let grid = detached(py, || {
            cells::grid_cells(&self.scene, size, z0, z1).map_err(|e| {
                err(
                    Kind::Cell,
                    format!("cannot make cells for {}: {e}", self.name),
                )
            })
        })?;
        Ok(PyBytes::new(py, &cells_to_bytes(&grid)))
    }

    /// The objects that may be visible in one frame (from-point culling: `hzb`, `hom`,
    /// `hom-approx`, `cplp`), as little-endian `u32` bytes.
    #[pyo3(signature = (eye, direction, fov_deg=60.0, width=1920, height=1080, method="hzb"))]
    #[allow(clippy::too_many_arguments)]
    fn visible_from<'py>(
        &self,
        py: Python<'py>,
        eye: [f64; 3],
        direction: [f64; 3],
        fov_deg: f64,
        width: u32,
        height: u32,
        method: &str,
    ) -> PyResult<Bound<'py, PyBytes>> {
        use sightline_geom::DVec3;
        let frustum = sightline_culling::Frustum::new(
            DVec3::from_array(eye),
            DVec3::from_array(direction),
            fov_deg,
            width,
            height,
        )
        .map_err(|e| err(Kind::Cell, e))?;
        let scene = self
            .culling
            .get_or_init(|| Arc::new(sightline_culling::CullScene::new(&self.scene)))
            .clone();
        let culler = sightline_culling::method(method, scene).map_err(|e| err(Kind::Method, e))?;
        let frame = detached(py, || Ok(culler.cull(&frustum, None)))?;
        Ok(PyBytes::new(py, &ids_to_bytes(&frame.visible)))
    }

    /// The PVS of one cell, as little-endian `u32` bytes.
    #[pyo3(signature = (cell, method, resolution=None, sweep=false, planes=None, knobs=Vec::new()))]
    #[allow(clippy::too_many_arguments)]
    fn pvs<'py>(
        &self,
        py: Python<'py>,
        cell: [f64; 6],
        method: &str,
        resolution: Option<u32>,
        sweep: bool,
        planes: Option<u32>,
        knobs: Vec<(String, String)>,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let c = self::cell(cell)?;
        let opts = method_options(method, resolution, sweep, planes, knobs)?;
        let ids = detached(py, || {
            self.method(method, &opts)?.pvs(&c).map_err(method_err)
        })?;
        Ok(PyBytes::new(py, &ids_to_bytes(&ids)))
    }

    /// The PVS of many cells (N×6 `f64` bytes) computed in parallel on `threads`.
    #[pyo3(signature = (cells, method, resolution=None, sweep=false, planes=None, threads=None, knobs=Vec::new()))]
    #[allow(clippy::too_many_arguments)]
    fn pvs_many<'py>(
        &self,
        py: Python<'py>,
        cells: &[u8],
        method: &str,
        resolution: Option<u32>,
        sweep: bool,
        planes: Option<u32>,
        threads: Option<usize>,
        knobs: Vec<(String, String)>,
    ) -> PyResult<Vec<Bound<'py, PyBytes>>> {
        let cells = cells_from_bytes(cells)?;
        let opts = method_options(method, resolution, sweep, planes, knobs)?;
        let pool = pool(threads)?;
        let sets = detached(py, || {
            let m = self.method(method, &opts)?;
            on_pool(pool.as_deref(), || {
                cells
                    .par_iter()
                    .enumerate()
                    .map(|(k, c)| {
                        m.pvs(c).map(|ids| ids_to_bytes(&ids)).map_err(|e| {
                            let msg = format!("cell {k} {}: {e}", c);
                            match e {
                                sightline_methods::MethodError::BadCell(_) => err(Kind::Cell, msg),
                                _ => err(Kind::Method, msg),
                            }
                        })
                    })
                    .collect::<PyResult<Vec<Vec<u8>>>>()
            })
        })?;
        Ok(sets.iter().map(|s| PyBytes::new(py, s)).collect())
    }

    /// The ground truth of one cell (`sightline truth --json`), as JSON text.
    #[pyo3(signature = (cell, samples=None, resolution=None))]
    fn truth_json(
        &self,
        py: Python<'_>,
        cell: [f64; 6],
        samples: Option<u32>,
        resolution: Option<u32>,
    ) -> PyResult<String> {
        let c = self::cell(cell)?;
        let opts = truth_options(samples, resolution)?;
        let truth = detached(py, || Ok(self.truth_scene().ground_truth(&c, &opts)))?;
        if truth.samples_used == 0 {
            return Err(err(
                Kind::Cell,
                format!("viewcell {c} has no free space (it lies inside a building or below the ground)"),
            ));
        }
        let v = serde_json::json!({
            "cell": c,
            "samples": opts.samples,
            "samples_used": truth.samples_used,
            "resolution": opts.resolution_px,
            "targeted_rays_per_object": opts.targeted_rays_per_object,
            "objects": self.scene.objects.len(),
            "visible": truth.visible,
            "found_by_rays": truth.found_by_rays,
            "seconds": truth.seconds,
        });
        serde_json::to_string(&v).map_err(|e| err(Kind::Scene, e))
    }
}

/// Truth options validated as the CLI's `truth`.
pub fn truth_options(samples: Option<u32>, resolution: Option<u32>) -> PyResult<TruthOptions> {
    let mut opts = TruthOptions::default();
    if let Some(s) = samples {
        if s == 0 || s > MAX_TRUTH_SAMPLES {
            return Err(err(
                Kind::Method,
                format!("samples must be between 1 and {MAX_TRUTH_SAMPLES}, got {s}"),
            ));
        }
        opts.samples = s;
    }
    if let Some(r) = resolution {
        if !(8..=MAX_TRUTH_RESOLUTION).contains(&r) {
            return Err(err(
                Kind::Method,
                format!("resolution must be between 8 and {MAX_TRUTH_RESOLUTION}, got {r}"),
            ));
        }
        opts.resolution_px = r;
    }
    Ok(opts)
}

/// Check a method name and its options as `build` would, without preparing anything.
#[pyfunction]
#[pyo3(signature = (method, resolution=None, sweep=false, planes=None, knobs=Vec::new()))]
pub fn check_method(
    method: &str,
    resolution: Option<u32>,
    sweep: bool,
    planes: Option<u32>,
    knobs: Vec<(String, String)>,
) -> PyResult<()> {
    method_options(method, resolution, sweep, planes, knobs).map(|_| ())
}

/// Parse `"x0,y0,z0,x1,y1,z1"` into six numbers, with the CLI's message.
#[pyfunction]
pub fn parse_cell(text: &str) -> PyResult<[f64; 6]> {
    text.parse::<ViewCell>()
        .map(|c| c.to_array())
        .map_err(|e| err(Kind::Cell, format!("bad viewcell '{text}': {e}")))
}

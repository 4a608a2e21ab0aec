//! The experiments of the papers that the report reproduces, each a function that appends raw [`Record`]s and
//! writes its section of the report.

use super::context::BenchContext;
use super::context::NamedScene;
use super::indoor::IndoorRecord;
use super::machine::Machine;
use super::meshes::{MeshLevel, MeshRecord};
use super::plots::{line_chart, Scale, Series};
use super::report::{Report, Table};
use super::suite::{Suite, NO_REPEAT_MS};
use anyhow::Context;
use rayon::prelude::*;
use serde::Serialize;
use sightline_core::check::{TruthOptions, TruthScene};
use sightline_geom::ViewCell;
use sightline_methods::{create, MethodOptions, VisibilityMethod};
use sightline_scene::Scene;
use sightline_stats::{loglog_slope, mean, median, quantile};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// The conservative methods, in the order of the method table (`erosion-rays`, the erosion paper's §7.1
/// variant, after the erosion family).
const CONSERVATIVE: &[&str] = &[
    "erosion",
    "erosion-segment",
    "erosion-cell",
    "shrink-sphere",
    "erosion-rays",
    "dual-ray",
    "dual-ray-exact",
    "ext-proj",
];
const FIG9: &[&str] = &[
    "shrink-sphere",
    "erosion-cell",
    "erosion-segment",
    "erosion",
];

/// One measured (method, cell) pair.
#[derive(Clone, Debug, Serialize)]
pub struct Record {
    pub experiment: String,
    pub scene: String,
    pub method: String,
    pub setting: String,
    pub cell_size_m: f64,
    pub cell: ViewCell,
    pub objects: usize,
    pub pvs: usize,
    /// |VS|, when the ground truth was computed for this record.
    pub vs: Option<usize>,
    pub missed: Option<usize>,
    pub over: Option<f64>,
    pub hidden_fraction: f64,
    /// Median over `timing_repeats` runs.
    pub ms: f64,
    /// The PVS itself (kept for the storage figure, not written to `raw.json`).
    #[serde(skip)]
    pub visible: Vec<u32>,
}

/// A scene under test with its cached ground truths.
pub struct Bench {
    pub suite: Suite,
    pub records: Vec<Record>,
    /// The indoor section's levels.
    pub indoor: Vec<IndoorRecord>,
    /// The mesh section's levels.
    pub meshes: Vec<MeshRecord>,
    pub notes: Vec<String>,
    pub from_point: Vec<super::from_point::FromPointRecord>,
    truths: HashMap<(String, String), Vec<u32>>,
    quiet: bool,
}

fn cell_key(c: &ViewCell) -> String {
    c.to_string()
}

/// Side of the forest-sweep cells (m). The sweep's fusion of leaves depends on the
/// cell being small against the leaves' umbrae: on the dense forest it culls ~40 % of
/// the trees from 0.5 m cells, ~70 % from 0.25 m, nothing from 1–2 m.
pub const FOREST_CELL_M: f64 = 0.5;

/// `n` cells of the `sightline cells` grid of `size_m`, spread evenly over the `8 n`
/// nearest the middle of the scene.
pub fn pick_cells(scene: &Scene, size_m: f64, n: usize) -> Vec<ViewCell> {
    let all = sightline_scene::cells::grid_cells(scene, size_m, 1.5, 2.0).unwrap_or_default();
    if all.len() <= n {
        return all;
    }
    sightline_core::check::near_middle(scene, &all, n, 8)
}

impl Bench {
    pub fn new(suite: Suite, quiet: bool) -> Self {
        Bench {
            suite,
            records: vec![],
            indoor: vec![],
            meshes: vec![],
            notes: vec![],
            from_point: vec![],
            truths: HashMap::new(),
            quiet,
        }
    }

    /// The part of the bench a section writes to.
    pub(crate) fn context(&mut self) -> BenchContext<'_> {
        BenchContext {
            suite: &self.suite,
            notes: &mut self.notes,
            quiet: self.quiet,
        }
    }

    pub(crate) fn log(&self, msg: &str) {
        if !self.quiet {
            eprintln!("bench: {msg}");
        }
    }

    pub(crate) fn truth_opts(&self) -> TruthOptions {
        let mut t = TruthOptions::default();
        if let Some(s) = self.suite.truth_samples {
            t.samples = s;
        }
        if let Some(r) = self.suite.truth_resolution_px {
            t.resolution_px = r;
        }
        t
    }

    /// Ground truths of `cells` (computed in parallel, cached per scene and cell).
    fn truths(&mut self, s: &NamedScene, cells: &[ViewCell]) -> Vec<Vec<u32>> {
        let opts = self.truth_opts();
        let missing: Vec<ViewCell> = cells
            .iter()
            .filter(|c| !self.truths.contains_key(&(s.name.clone(), cell_key(c))))
            .copied()
            .collect();
        if missing.is_empty() {
            return cells
                .iter()
                .map(|c| self.truths[&(s.name.clone(), cell_key(c))].clone())
                .collect();
        }
        let ts = TruthScene::new(&s.scene);
        let computed: Vec<(ViewCell, Vec<u32>)> = missing
            .par_iter()
            .map(|c| (*c, ts.ground_truth(c, &opts).visible))
            .collect();
        for (c, v) in computed {
            self.truths.insert((s.name.clone(), cell_key(&c)), v);
        }
        cells
            .iter()
            .map(|c| self.truths[&(s.name.clone(), cell_key(c))].clone())
            .collect()
    }

    /// Prepare `method` or record why it is not available.
    fn method(
        &mut self,
        s: &NamedScene,
        name: &str,
        opts: &MethodOptions,
    ) -> Option<Box<dyn VisibilityMethod>> {
        match create(name, s.scene.clone(), opts) {
            Ok(m) => Some(m),
            Err(e) => {
                self.notes
                    .push(format!("`{name}` failed to prepare on {}: {e}", s.name));
                None
            }
        }
    }

    /// Run `m` on every cell (median of repeats), compare with truth when given.
    #[allow(clippy::too_many_arguments)]
    fn measure(
        &mut self,
        experiment: &str,
        s: &NamedScene,
        m: &dyn VisibilityMethod,
        setting: &str,
        size_m: f64,
        cells: &[ViewCell],
        truths: Option<&[Vec<u32>]>,
    ) -> Vec<Record> {
        let n_obj = s.scene.objects.len();
        let mut out = Vec::with_capacity(cells.len());
        for (i, cell) in cells.iter().enumerate() {
            let mut times = Vec::with_capacity(self.suite.timing_repeats);
            let mut pvs = Vec::new();
            let mut failed = None;
            for _ in 0..self.suite.timing_repeats.max(1) {
                let t = Instant::now();
                match m.pvs(cell) {
                    Ok(p) => pvs = p,
                    Err(e) => {
                        failed = Some(e.to_string());
                        break;
                    }
                }
                let ms = t.elapsed().as_secs_f64() * 1e3;
                times.push(ms);
                if ms > NO_REPEAT_MS {
                    break;
                }
            }
            if let Some(e) = failed {
                self.notes.push(format!(
                    "`{}` failed on {} cell {cell}: {e}",
                    m.name(),
                    s.name
                ));
                continue;
            }
            let (vs, missed, over) = match truths {
                Some(t) => {
                    let vs = &t[i];
                    let missed = vs
                        .iter()
                        .filter(|id| pvs.binary_search(id).is_err())
                        .count();
                    let over = pvs.len() as f64 / vs.len().max(1) as f64;
                    (Some(vs.len()), Some(missed), Some(over))
                }
                None => (None, None, None),
            };
            out.push(Record {
                experiment: experiment.into(),
                scene: s.name.clone(),
                method: m.name().into(),
                setting: setting.into(),
                cell_size_m: size_m,
                cell: *cell,
                objects: n_obj,
                pvs: pvs.len(),
                vs,
                missed,
                over,
                hidden_fraction: 1.0 - pvs.len() as f64 / n_obj.max(1) as f64,
                ms: median(&times),
                visible: pvs,
            });
        }
        self.records.extend(out.iter().cloned());
        out
    }
}

fn summarize(recs: &[Record]) -> (f64, f64, f64, f64, usize, f64) {
    let overs: Vec<f64> = recs.iter().filter_map(|r| r.over).collect();
    let ms: Vec<f64> = recs.iter().map(|r| r.ms).collect();
    let missed: usize = recs.iter().filter_map(|r| r.missed).sum();
    let hidden: Vec<f64> = recs.iter().map(|r| r.hidden_fraction).collect();
    (
        median(&overs),
        quantile(&overs, 0.9),
        median(&ms),
        quantile(&ms, 0.9),
        missed,
        mean(&hidden),
    )
}

fn f(v: f64, digits: usize) -> String {
    if v.is_finite() {
        format!("{v:.digits$}")
    } else {
        "–".into()
    }
}

/// Erosion paper Fig. 9: mean `over` vs cell size for methods 1–4, and the ratio 1/4.
fn fig9(b: &mut Bench, scenes: &[NamedScene], rep: &mut Report, out: &Path) -> anyhow::Result<()> {
    rep.section("Erosion family vs viewcell size (erosion paper, Fig. 9)");
    rep.para("Mean `over` = |PVS| / |VS| per cell size, on street cells spread over each scene; the last column is the ratio method 1 / method 4 (shrink-sphere / erosion), the lower curve of Fig. 9.");
    for s in scenes {
        b.log(&format!("fig9 on {}", s.name));
        let mut table = Table::new(&[
            "cell size (m)",
            "cells",
            "shrink-sphere",
            "erosion-cell",
            "erosion-segment",
            "erosion",
            "missed",
            "ratio 1/4",
        ]);
        let mut series: Vec<Series> = FIG9
            .iter()
            .map(|m| Series {
                name: m.to_string(),
                points: vec![],
            })
            .collect();
        let mut ratio = Series {
            name: "shrink-sphere / erosion".into(),
            points: vec![],
        };
        let methods: Vec<Option<Box<dyn VisibilityMethod>>> = FIG9
            .iter()
            .map(|m| b.method(s, m, &MethodOptions::default()))
            .collect();
        if methods.iter().all(Option::is_none) {
            rep.para(&format!(
                "{}: no erosion-family method is available.",
                s.name
            ));
            continue;
        }
        for &size in &b.suite.cell_sizes_m.clone() {
            let cells = pick_cells(&s.scene, size, b.suite.cells_per_setting);
            if cells.is_empty() {
                continue;
            }
            let truths = b.truths(s, &cells);
            let mut means = vec![f64::NAN; FIG9.len()];
            let mut missed = 0;
            for (k, m) in methods.iter().enumerate() {
                if let Some(m) = m {
                    let recs = b.measure("fig9", s, m.as_ref(), "", size, &cells, Some(&truths));
                    let overs: Vec<f64> = recs.iter().filter_map(|r| r.over).collect();
                    means[k] = mean(&overs);
                    missed += recs.iter().filter_map(|r| r.missed).sum::<usize>();
                    series[k].points.push((size, means[k]));
                }
            }
            let r = means[0] / means[3];
            ratio.points.push((size, r));
            let mut row = vec![f(size, 0), cells.len().to_string()];
            row.extend(means.iter().map(|v| f(*v, 2)));
            row.push(missed.to_string());
            row.push(f(r, 2));
            table.row(row);
        }
        rep.para(&format!(
            "**{}** ({} objects):",
            s.name,
            s.scene.objects.len()
        ));
        rep.table(&table);
        let png = format!("fig9-{}.png", s.name);
        series.push(ratio);
        series.retain(|s| !s.points.is_empty());
        if !series.is_empty() {
            line_chart(
                &out.join(&png),
                &format!("Over-conservativity vs cell size — {}", s.name),
                "viewcell size (m)",
                "mean |PVS| / |VS|",
                &series,
                Scale::Log,
                Scale::Linear,
            )?;
            rep.image(&png, "over vs cell size");
        }
    }
    Ok(())
}

/// Dual ray space paper Table 1: time and over-estimation vs resolution × cell size.
fn table1(b: &mut Bench, rep: &mut Report, out: &Path) -> anyhow::Result<()> {
    rep.section("Dual ray space: resolution × cell size (dual ray space paper, Table 1)");
    let n = b.suite.metropolis_buildings;
    b.log(&format!("table1 on a {n}-building metropolis"));
    let s = NamedScene {
        name: format!("metropolis-{n}"),
        scene: Arc::new(sightline_scene::generate::metropolis(b.suite.seed, n)),
    };
    let Some(exact) = b.method(&s, "dual-ray-exact", &MethodOptions::default()) else {
        rep.para("`dual-ray-exact` is not available: Table 1 skipped.");
        return Ok(());
    };
    rep.para(&format!("Scene: generated metropolis, {} objects, cells 2 m high (z 0.5–2.5 m). Over-estimation is the object-level analogue of the paper's measure: (|PVS(res)| − |PVS(exact)|) / |PVS(exact)|, in %. Times are medians per cell, single thread.", s.scene.objects.len()));
    let mut table = Table::new(&[
        "resolution",
        "ms @50 m",
        "ms @100 m",
        "ms @300 m",
        "over-est. % @50",
        "@100",
        "@300",
    ]);
    let sizes = b.suite.dual_ray_cell_sizes_m.clone();
    let mut exact_sizes = Vec::new();
    let mut cellsets = Vec::new();
    for &size in &sizes {
        let cells: Vec<ViewCell> = pick_cells(&s.scene, size, b.suite.cells_per_setting.min(3))
            .into_iter()
            .filter_map(|c| {
                ViewCell::from_array([c.min.x, c.min.y, 0.5, c.max.x, c.max.y, 2.5]).ok()
            })
            .collect();
        let recs = b.measure("table1", &s, exact.as_ref(), "exact", size, &cells, None);
        exact_sizes.push(recs.iter().map(|r| r.pvs as f64).collect::<Vec<_>>());
        cellsets.push(cells);
    }
    let mut time_series: Vec<Series> = sizes
        .iter()
        .map(|s| Series {
            name: format!("{s:.0} m cells"),
            points: vec![],
        })
        .collect();
    for &res in &b.suite.dual_ray_resolutions.clone() {
        let opts = MethodOptions {
            resolution_px: Some(res),
            ..Default::default()
        };
        let Some(m) = b.method(&s, "dual-ray", &opts) else {
            rep.para("`dual-ray` is not available.");
            return Ok(());
        };
        let mut ms = vec![];
        let mut est = vec![];
        for (k, &size) in sizes.iter().enumerate() {
            let recs = b.measure(
                "table1",
                &s,
                m.as_ref(),
                &format!("res={res}"),
                size,
                &cellsets[k],
                None,
            );
            let t = median(&recs.iter().map(|r| r.ms).collect::<Vec<_>>());
            let e: Vec<f64> = recs
                .iter()
                .zip(&exact_sizes[k])
                .map(|(r, pe)| 100.0 * (r.pvs as f64 - pe) / pe.max(1.0))
                .collect();
            time_series[k].points.push((res as f64, t));
            ms.push(t);
            est.push(mean(&e));
        }
        let mut row = vec![format!("{res}²")];
        row.extend(ms.iter().map(|v| f(*v, 1)));
        row.extend(est.iter().map(|v| f(*v, 2)));
        table.row(row);
    }
    rep.table(&table);
    line_chart(
        &out.join("table1-time.png"),
        "dual-ray: time per cell vs resolution",
        "ray-space resolution (px)",
        "ms per cell (median)",
        &time_series,
        Scale::Log,
        Scale::Log,
    )?;
    rep.image("table1-time.png", "dual-ray time vs resolution");
    Ok(())
}

/// Extended projections: Fig. 12 (resolution curve) and the forest sweep (§7.2).
fn ext_proj(b: &mut Bench, city: &NamedScene, rep: &mut Report, out: &Path) -> anyhow::Result<()> {
    rep.section("Extended projections: depth-map resolution and the occlusion sweep (ext. proj. paper, Fig. 12 and §7.2)");
    let cells = pick_cells(&city.scene, 25.0, b.suite.cells_per_setting);
    let mut table = Table::new(&[
        "resolution",
        "ms/cell (median)",
        "% hidden",
        "over (median)",
        "missed",
    ]);
    let truths = b.truths(city, &cells);
    let mut t_series = Series {
        name: "ms per cell".into(),
        points: vec![],
    };
    let mut h_series = Series {
        name: "% hidden".into(),
        points: vec![],
    };
    for &res in &b.suite.ext_proj_resolutions.clone() {
        let opts = MethodOptions {
            resolution_px: Some(res),
            ..Default::default()
        };
        let Some(m) = b.method(city, "ext-proj", &opts) else {
            rep.para("`ext-proj` is not available.");
            return Ok(());
        };
        let recs = b.measure(
            "fig12",
            city,
            m.as_ref(),
            &format!("res={res}"),
            25.0,
            &cells,
            Some(&truths),
        );
        let (om, _, tm, _, missed, hidden) = summarize(&recs);
        t_series.points.push((res as f64, tm));
        h_series.points.push((res as f64, 100.0 * hidden));
        table.row(vec![
            res.to_string(),
            f(tm, 1),
            f(100.0 * hidden, 1),
            f(om, 2),
            missed.to_string(),
        ]);
    }
    rep.para(&format!(
        "{} ({} objects), 25 m street cells:",
        city.name,
        city.scene.objects.len()
    ));
    rep.table(&table);
    line_chart(
        &out.join("fig12-time.png"),
        "ext-proj: time vs depth-map resolution",
        "resolution (px)",
        "ms per cell",
        &[t_series],
        Scale::Log,
        Scale::Log,
    )?;
    line_chart(
        &out.join("fig12-hidden.png"),
        "ext-proj: % hidden vs depth-map resolution",
        "resolution (px)",
        "% of objects hidden",
        &[h_series],
        Scale::Log,
        Scale::Linear,
    )?;
    rep.image("fig12-time.png", "time vs resolution");
    rep.image("fig12-hidden.png", "hidden vs resolution");

    let trees = b.suite.forest_trees;
    b.log(&format!("forest sweep on {trees} trees"));
    // The dense forest (crowns down to the ground, overlapping): in the default one the
    // ground truth sees every tree from inside, so there is nothing to cull.
    let fp = sightline_scene::generate::ForestParams::dense(trees);
    let forest = NamedScene {
        name: format!("dense-forest-{trees}"),
        scene: Arc::new(sightline_scene::generate::forest_with(b.suite.seed, &fp)),
    };
    let tris: usize = forest
        .scene
        .objects
        .iter()
        .map(|o| o.triangle_count())
        .sum();
    let cells = fp.cells_between_trees(FOREST_CELL_M, b.suite.cells_per_setting);
    let truths = b.truths(&forest, &cells);
    let mut table = Table::new(&[
        "variant",
        "ms/cell (median)",
        "% objects culled",
        "over (median)",
        "missed",
    ]);
    let mut variants: Vec<(String, MethodOptions)> =
        vec![("ext-proj (no sweep)".into(), MethodOptions::default())];
    for &p in &b.suite.sweep_planes {
        variants.push((
            format!("sweep, {p} planes"),
            MethodOptions {
                sweep: true,
                planes: Some(p),
                ..Default::default()
            },
        ));
    }
    for (label, opts) in variants {
        let Some(m) = b.method(&forest, "ext-proj", &opts) else {
            continue;
        };
        let recs = b.measure(
            "sweep",
            &forest,
            m.as_ref(),
            &label,
            FOREST_CELL_M,
            &cells,
            Some(&truths),
        );
        let (om, _, tm, _, missed, hidden) = summarize(&recs);
        table.row(vec![
            label,
            f(tm, 1),
            f(100.0 * hidden, 1),
            f(om, 2),
            missed.to_string(),
        ]);
    }
    rep.para(&format!(
        "Generated dense forest: {trees} trees, {} objects, {tris} triangles, {FOREST_CELL_M} m cells between trees:",
        forest.scene.objects.len()
    ));
    rep.table(&table);
    Ok(())
}

/// All conservative methods on the same cells.
fn side_by_side(
    b: &mut Bench,
    scenes: &[NamedScene],
    names: &[String],
    rep: &mut Report,
) -> anyhow::Result<()> {
    rep.section("All methods on the same cells");
    rep.para("Per method: ms per cell (median, p90), `over` = |PVS|/|VS| (median, p90), total `missed` (must be 0 for every conservative method), mean hidden fraction, and bytes per cell of a `.pvs` holding these cells' sets (compressed sets only; the cells are scattered, so the delta-PVS between neighbours cannot help as it does on a grid).");
    for s in scenes {
        let size = 25.0;
        let cells = pick_cells(&s.scene, size, b.suite.cells_per_setting * 2);
        let truths = b.truths(s, &cells);
        let mut table = Table::new(&[
            "method",
            "cells",
            "ms median",
            "ms p90",
            "over median",
            "over p90",
            "missed",
            "hidden %",
            "bytes/cell",
        ]);
        for name in names {
            let Some(m) = b.method(s, name, &MethodOptions::default()) else {
                continue;
            };
            let recs = b.measure(
                "side-by-side",
                s,
                m.as_ref(),
                "",
                size,
                &cells,
                Some(&truths),
            );
            let (om, op, tm, tp, missed, hidden) = summarize(&recs);
            let bytes = stored_bytes_per_cell(s, m.as_ref(), &recs)
                .map_or_else(|| "—".to_string(), |v| f(v, 1));
            table.row(vec![
                name.clone(),
                recs.len().to_string(),
                f(tm, 2),
                f(tp, 2),
                f(om, 2),
                f(op, 2),
                missed.to_string(),
                f(100.0 * hidden, 1),
                bytes,
            ]);
        }
        rep.para(&format!(
            "**{}** ({} objects), {size:.0} m street cells:",
            s.name,
            s.scene.objects.len()
        ));
        rep.table(&table);
    }
    Ok(())
}

/// Bytes per cell of the DATA section of a `.pvs` holding the records' sets.
fn stored_bytes_per_cell(s: &NamedScene, m: &dyn VisibilityMethod, recs: &[Record]) -> Option<f64> {
    if recs.is_empty() {
        return None;
    }
    let cells: Vec<ViewCell> = recs.iter().map(|r| r.cell).collect();
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    let sets: Vec<Vec<u32>> = recs.iter().map(|r| r.visible.clone()).collect();
    let header = sightline_pvs::format::Header::new(
        s.scene.fingerprint(),
        m.name(),
        m.params(),
        s.scene.objects.len(),
        cells.len(),
    );
    let bytes = sightline_pvs::format::encode(&header, &cells, &present, &sets).ok()?;
    let file = sightline_pvs::PvsFile::from_bytes(bytes).ok()?;
    Some(file.sizes().0 as f64 / cells.len() as f64)
}

/// ms/cell vs number of buildings, log-log with the fitted exponent; and the PVS size,
/// its exponent and the ms per visible object, which show whether a method's cost
/// follows its output.
fn scaling(b: &mut Bench, names: &[String], rep: &mut Report, out: &Path) -> anyhow::Result<()> {
    rep.section("Scaling with scene size");
    // Per method: (buildings, median ms, median |PVS|).
    let mut per_method: HashMap<String, Vec<(f64, f64, f64)>> = HashMap::new();
    for &n in &b.suite.scaling_buildings.clone() {
        b.log(&format!("scaling on {n} buildings"));
        let s = NamedScene {
            name: format!("metropolis-{n}"),
            scene: Arc::new(sightline_scene::generate::metropolis(b.suite.seed, n)),
        };
        let cells = pick_cells(&s.scene, 100.0, b.suite.scaling_cells.max(1));
        for name in names {
            let Some(m) = b.method(&s, name, &MethodOptions::default()) else {
                continue;
            };
            let recs = b.measure("scaling", &s, m.as_ref(), "", 100.0, &cells, None);
            let t = median(&recs.iter().map(|r| r.ms).collect::<Vec<_>>());
            let pvs = median(
                &recs
                    .iter()
                    .map(|r| r.visible.len() as f64)
                    .collect::<Vec<_>>(),
            );
            per_method.entry(name.clone()).or_default().push((
                s.scene.objects.len() as f64,
                t,
                pvs,
            ));
        }
    }
    let mut table = Table::new(&[
        "method",
        "ms/cell at each size",
        "fitted exponent",
        "|PVS| at each size",
        "|PVS| exponent",
        "ms per visible object",
    ]);
    let mut series = Vec::new();
    let mut keys: Vec<&String> = per_method.keys().collect();
    keys.sort();
    for k in keys {
        let pts = &per_method[k];
        let join = |cell: &dyn Fn(&(f64, f64, f64)) -> String| {
            pts.iter().map(cell).collect::<Vec<_>>().join(", ")
        };
        let ms: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1)).collect();
        let pvs: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.2)).collect();
        table.row(vec![
            k.clone(),
            join(&|p| format!("{:.0}: {:.2}", p.0, p.1)),
            f(loglog_slope(&ms), 2),
            join(&|p| format!("{:.0}: {:.0}", p.0, p.2)),
            f(loglog_slope(&pvs), 2),
            join(&|p| format!("{:.0}: {:.3}", p.0, p.1 / p.2.max(1.0))),
        ]);
        series.push(Series {
            name: k.clone(),
            points: ms,
        });
    }
    rep.para(&format!(
        "Median ms per 100 m cell ({} cells per size) on generated metropolises of growing size (the extended projections paper reports growth close to √n), the median PVS size and the ms per visible object (a method whose cost follows its output has the two exponents close):",
        b.suite.scaling_cells.max(1)
    ));
    rep.table(&table);
    if !series.is_empty() {
        line_chart(
            &out.join("scaling.png"),
            "time per cell vs scene size",
            "buildings",
            "ms per cell (median)",
            &series,
            Scale::Log,
            Scale::Log,
        )?;
        rep.image("scaling.png", "scaling");
    }
    Ok(())
}

/// Which parts of the suite run: the city experiments, the indoor section on
/// `levels` (`.bsp` files; none skips it) and the mesh section on `meshes` (none skips
/// it).
#[derive(Clone, Debug)]
pub struct Sections {
    pub cities: bool,
    pub levels: Vec<PathBuf>,
    pub meshes: Vec<MeshLevel>,
}

impl Default for Sections {
    fn default() -> Self {
        Sections {
            cities: true,
            levels: Vec::new(),
            meshes: Vec::new(),
        }
    }
}

/// Run a suite and write `out/README.md`, `out/raw.json` and the plots.
pub fn run(
    suite: Suite,
    extra: &[PathBuf],
    methods: Option<Vec<String>>,
    sections: &Sections,
    out: &Path,
    quiet: bool,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let started = Instant::now();
    let names: Vec<String> =
        methods.unwrap_or_else(|| CONSERVATIVE.iter().map(|s| s.to_string()).collect());
    for n in &names {
        if !sightline_methods::METHOD_NAMES.contains(&n.as_str()) {
            anyhow::bail!("unknown method '{n}'");
        }
    }
    let mut b = Bench::new(suite.clone(), quiet);
    let mut scenes = vec![NamedScene {
        name: format!("city-{}", suite.city_buildings),
        scene: Arc::new(sightline_scene::generate::city(
            suite.seed,
            suite.city_buildings,
        )),
    }];
    for p in extra {
        let scene = sightline_scene::import::load(p, &Default::default())
            .with_context(|| format!("cannot load {}", p.display()))?;
        let name = p
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("scene")
            .to_string();
        scenes.push(NamedScene {
            name,
            scene: Arc::new(scene),
        });
    }
    let machine = Machine::detect();
    let mut rep = Report::new(&suite, &machine);
    type Experiment<'a> = Box<dyn FnOnce(&mut Bench, &mut Report) -> anyhow::Result<()> + 'a>;
    let mut experiments: Vec<(&str, Experiment)> = Vec::new();
    if sections.cities {
        experiments.push(("Fig. 9", Box::new(|b, r| fig9(b, &scenes, r, out))));
        experiments.push((
            "side by side",
            Box::new(|b, r| side_by_side(b, &scenes, &names, r)),
        ));
        experiments.push(("Table 1", Box::new(|b, r| table1(b, r, out))));
        experiments.push((
            "Fig. 12 + sweep",
            Box::new(|b, r| ext_proj(b, &scenes[0], r, out)),
        ));
        experiments.push(("scaling", Box::new(|b, r| scaling(b, &names, r, out))));
        experiments.push((
            "from-point",
            Box::new(|b, r| {
                let mut records = Vec::new();
                let done =
                    super::from_point::from_point(&mut b.context(), &mut records, &scenes, r, out);
                b.from_point.extend(records);
                done
            }),
        ));
    }
    // One experiment per level, so that raw.json is written after each (a long run that
    // is stopped keeps its levels), then the section.
    let level_names: Vec<String> = sections
        .levels
        .iter()
        .map(|p| format!("indoor {}", p.display()))
        .collect();
    for (path, name) in sections.levels.iter().zip(&level_names) {
        experiments.push((
            name.as_str(),
            Box::new(move |b, _| {
                let (suite, quiet) = (b.suite.clone(), b.quiet);
                super::indoor::measure_into(&suite, path, &mut b.indoor, &mut b.notes, quiet);
                Ok(())
            }),
        ));
    }
    if !sections.levels.is_empty() {
        experiments.push((
            "indoor report",
            Box::new(|b, r| super::indoor::write_section(&b.suite, &b.indoor, r, out)),
        ));
    }
    // Likewise one experiment per mesh level, then the section.
    let mesh_names: Vec<String> = sections
        .meshes
        .iter()
        .map(|m| format!("meshes {}", m.name()))
        .collect();
    for (level, name) in sections.meshes.iter().zip(&mesh_names) {
        experiments.push((
            name.as_str(),
            Box::new(move |b, _| {
                let (suite, quiet, truth) = (b.suite.clone(), b.quiet, b.truth_opts());
                super::meshes::measure_into(
                    &suite,
                    level,
                    &truth,
                    &mut b.meshes,
                    &mut b.notes,
                    quiet,
                );
                Ok(())
            }),
        ));
    }
    if !sections.meshes.is_empty() {
        experiments.push((
            "meshes report",
            Box::new(|b, r| super::meshes::write_section(&b.meshes, r, out)),
        ));
    }
    let known: Vec<&str> = experiments.iter().map(|e| e.0).collect();
    let experiments: Vec<(&str, Experiment)> = match &suite.only {
        None => experiments,
        Some(only) => {
            for o in only {
                if !known.iter().any(|k| selects(o, k)) {
                    anyhow::bail!("unknown experiment '{o}' (known: {})", known.join(", "));
                }
            }
            experiments
                .into_iter()
                .filter(|e| only.iter().any(|o| selects(o, e.0)))
                .collect()
        }
    };
    anyhow::ensure!(
        !experiments.is_empty(),
        "nothing to run: --indoor-only needs a level (--levels LEVEL.bsp|FOLDER) or --meshes"
    );
    let total = experiments.len();
    let mut parts: Vec<(&str, f64)> = Vec::new();
    for (name, run) in experiments {
        let t = Instant::now();
        run(&mut b, &mut rep)?;
        parts.push((name, t.elapsed().as_secs_f64()));
        // Written after every experiment: a long suite that is stopped keeps what it did.
        let done = parts.len() == total;
        write_report(&suite, &machine, &b, &rep, started, &parts, done, out)?;
    }
    Ok(())
}

/// Whether `--only` entry `o` selects experiment `name`: its name, or its section
/// (`indoor`, `meshes`: every experiment of the section), case-insensitive.
fn selects(o: &str, name: &str) -> bool {
    name.eq_ignore_ascii_case(o)
        || name
            .split_once(' ')
            .is_some_and(|(section, _)| section.eq_ignore_ascii_case(o))
            && ["indoor", "meshes"]
                .iter()
                .any(|s| s.eq_ignore_ascii_case(o))
}

/// `out/README.md` (with the notes and the footer) and `out/raw.json` as they stand;
/// `done` is false while experiments remain.
#[allow(clippy::too_many_arguments)]
fn write_report(
    suite: &Suite,
    machine: &Machine,
    b: &Bench,
    rep: &Report,
    started: Instant,
    parts: &[(&str, f64)],
    done: bool,
    out: &Path,
) -> anyhow::Result<()> {
    let mut rep = rep.clone();
    rep.notes(&b.notes);
    rep.footer(started.elapsed().as_secs_f64(), parts, done);
    crate::common::write_atomic(&out.join("README.md"), rep.markdown().as_bytes())?;
    #[derive(Serialize)]
    struct Raw<'a> {
        suite: &'a Suite,
        machine: &'a Machine,
        records: &'a [Record],
        indoor: &'a [IndoorRecord],
        meshes: &'a [MeshRecord],
        from_point: &'a [super::from_point::FromPointRecord],
        notes: &'a [String],
    }
    let raw = serde_json::to_vec_pretty(&Raw {
        suite,
        machine,
        records: &b.records,
        indoor: &b.indoor,
        meshes: &b.meshes,
        from_point: &b.from_point,
        notes: &b.notes,
    })?;
    crate::common::write_atomic(&out.join("raw.json"), &raw)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The whole pipeline on scenes small enough for a unit test: every experiment
    /// writes its section, every conservative record has `missed == 0`, and the
    /// report ends with the timed footer.
    #[test]
    fn a_tiny_suite_writes_a_complete_report() {
        let suite = Suite {
            name: "tiny".into(),
            seed: 3,
            city_buildings: 40,
            cell_sizes_m: vec![25.0],
            cells_per_setting: 1,
            timing_repeats: 1,
            metropolis_buildings: 200,
            dual_ray_cell_sizes_m: vec![50.0],
            dual_ray_resolutions: vec![16, 32],
            ext_proj_resolutions: vec![64],
            forest_trees: 6,
            sweep_planes: vec![1],
            scaling_buildings: vec![100, 200],
            scaling_cells: 1,
            truth_samples: Some(8),
            truth_resolution_px: Some(64),
            indoor_sources: 4,
            from_point_frames: 3,
            from_point_size: (160, 90),
            from_point_full_every: 1,
            from_point_truth_every: 1,
            from_point_walk_frames: 3,
            from_point_scenes: vec![],
            mesh_viewcells: Some(2),
            mesh_judged: 1,
            only: None,
            vis_reference: None,
            vis_prt: None,
        };
        let dir = std::env::temp_dir().join(format!("sightline-bench-{}", std::process::id()));
        let methods = vec!["dual-ray".to_string(), "dual-ray-exact".to_string()];
        run(suite, &[], Some(methods), &Sections::default(), &dir, true).unwrap();
        let md = std::fs::read_to_string(dir.join("README.md")).unwrap();
        for section in [
            "Fig. 9",
            "All methods on the same cells",
            "Table 1",
            "Fig. 12",
            "Scaling",
            "From-point culling",
        ] {
            assert!(md.contains(section), "missing section {section}:\n{md}");
        }
        assert!(md.contains("Suite ran in"), "{md}");
        assert!(dir.join("table1-time.png").exists());
        assert!(dir.join("walk-visible.png").exists(), "{md}");
        let raw: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("raw.json")).unwrap()).unwrap();
        let records = raw["records"].as_array().unwrap();
        for r in raw["from_point"].as_array().unwrap() {
            for c in r["cullers"].as_array().unwrap() {
                assert_eq!(c["false_culls"].as_u64(), Some(0), "{r}");
            }
        }

        assert!(!records.is_empty());
        for r in records {
            if let Some(m) = r["missed"].as_u64() {
                assert_eq!(m, 0, "{r}");
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}

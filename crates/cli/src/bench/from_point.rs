//! The from-point section (`docs/culling.md`, issue 40): occluder triangles per second per core
//! of the masked tile rasterizer (scalar and SIMD paths) next to the full-resolution
//! rasterizer of `sightline-raster` on the same faces in the same run; what `hzb` culls
//! against a full-resolution depth buffer of the same occluders (the measure Masked
//! Occlusion Culling reports, Hasselgren et al. 2016 §5); ms per frame of `hzb`, `hom`
//! and `cplp`; false culls against the item-buffer truth; and the walk plot, visible
//! objects along a walk with the PVS of the eye's cell alone and with from-point culling
//! inside it.

use super::context::{BenchContext, NamedScene};
use super::plots::{line_chart, Scale, Series};
use super::report::{Report, Table};
use super::suite::Suite;
use serde::Serialize;
use sightline_culling::masked::RasterPath;
use sightline_culling::measure::{full_res, full_res_occluded, masked_throughput};
use sightline_culling::truth::FrameTruth;
use sightline_culling::walk::{street_walk, PathFrame};
use sightline_culling::{method, CullScene, Culler, Frustum};
use sightline_geom::DVec3;
use sightline_geom::ViewCell;
use sightline_methods::{create, MethodOptions};
use sightline_stats::{median, quantile};
use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// The conservative cullers, in the order of the table.
const CULLERS: &[&str] = &["hzb", "hom", "cplp"];
/// The from-region method giving the first level of the walk plot, and its cells' side.
const PVS_METHOD: &str = "erosion";
const PVS_CELL_M: f64 = 25.0;

/// Raw figures of one scene (in `raw.json`).
#[derive(Clone, Debug, Serialize)]
pub struct FromPointRecord {
    pub scene: String,
    pub objects: usize,
    pub frames: usize,
    pub size: [u32; 2],
    pub simd_level: String,
    /// Medians over the frames of the per-frame rate.
    pub scalar_tris_per_s: f64,
    pub simd_tris_per_s: f64,
    pub full_res_tris_per_s: f64,
    pub tris_per_frame: f64,
    /// `hzb`'s occlusion-culled objects over the full-resolution buffer's, same frames.
    pub hzb_vs_full_res_pct: f64,
    pub cullers: Vec<CullerRecord>,
}

#[derive(Clone, Debug, Serialize)]
pub struct CullerRecord {
    pub method: String,
    pub culled_pct: f64,
    pub median_ms: f64,
    pub p90_ms: f64,
    pub false_culls: usize,
    pub truth_frames: usize,
}

fn frustum_of(pf: &PathFrame, (w, h): (u32, u32)) -> anyhow::Result<Frustum> {
    Ok(Frustum::new(
        DVec3::from_array(pf.eye),
        DVec3::from_array(pf.dir),
        pf.fov_deg,
        w,
        h,
    )?)
}

fn m(v: f64) -> String {
    format!("{:.2}", v / 1e6)
}

/// Measure one scene along a street walk.
fn measure_scene(su: &Suite, s: &NamedScene) -> anyhow::Result<FromPointRecord> {
    let size = su.from_point_size;
    let walk = street_walk(&s.scene, su.from_point_frames, su.seed, 60.0);
    if walk.is_empty() {
        anyhow::bail!("no street-level point in {}", s.name);
    }
    let cs = Arc::new(CullScene::new(&s.scene));
    let truth = FrameTruth::new(&s.scene);
    let cullers: Vec<Box<dyn Culler>> = CULLERS
        .iter()
        .map(|n| method(n, cs.clone()))
        .collect::<Result<_, _>>()?;
    let mut ms = vec![Vec::new(); cullers.len()];
    let mut culled = vec![0usize; cullers.len()];
    let mut false_culls = vec![0usize; cullers.len()];
    let (mut truth_frames, mut candidates) = (0usize, 0usize);
    let (mut scalar, mut simd, mut full) = (Vec::new(), Vec::new(), Vec::new());
    let (mut tris, mut hzb_occl, mut full_occl) = (0u64, 0usize, 0usize);
    for (k, pf) in walk.iter().enumerate() {
        let f = frustum_of(pf, size)?;
        candidates += cs.objects();
        let mut answers = Vec::new();
        for (i, c) in cullers.iter().enumerate() {
            let t = Instant::now();
            let fr = c.cull(&f, None);
            ms[i].push(t.elapsed().as_secs_f64() * 1e3);
            culled[i] += fr.candidates - fr.visible.len();
            answers.push(fr);
        }
        let ts = masked_throughput(&cs, &f, RasterPath::Scalar);
        let tv = masked_throughput(&cs, &f, RasterPath::Simd);
        tris += tv.tris;
        scalar.push(ts.tris_per_s());
        simd.push(tv.tris_per_s());
        if k % su.from_point_full_every == 0 {
            let (fb, t) = full_res(&cs, &f);
            full.push(t.tris_per_s());
            full_occl += full_res_occluded(&cs, &f, &fb);
            hzb_occl += answers[0].occlusion_culled;
        }
        if k % su.from_point_truth_every == 0 {
            truth_frames += 1;
            let vs = truth.visible(&f);
            for (i, fr) in answers.iter().enumerate() {
                false_culls[i] += vs
                    .iter()
                    .filter(|id| fr.visible.binary_search(id).is_err())
                    .count();
            }
        }
    }
    Ok(FromPointRecord {
        scene: s.name.clone(),
        objects: cs.objects(),
        frames: walk.len(),
        size: [size.0, size.1],
        simd_level: RasterPath::Simd.describe(),
        scalar_tris_per_s: median(&scalar),
        simd_tris_per_s: median(&simd),
        full_res_tris_per_s: median(&full),
        tris_per_frame: tris as f64 / walk.len() as f64,
        hzb_vs_full_res_pct: 100.0 * hzb_occl as f64 / full_occl.max(1) as f64,
        cullers: cullers
            .iter()
            .enumerate()
            .map(|(i, c)| CullerRecord {
                method: c.name().into(),
                culled_pct: 100.0 * culled[i] as f64 / candidates.max(1) as f64,
                median_ms: median(&ms[i]),
                p90_ms: quantile(&ms[i], 0.9),
                false_culls: false_culls[i],
                truth_frames,
            })
            .collect(),
    })
}

/// Visible objects along a walk: the PVS of the eye's cell (a [`PVS_CELL_M`] grid cell,
/// `erosion`, computed on line and cached), and `hzb` inside it. Returns the two series
/// and the median share of the PVS the second level removes.
fn walk_plot(su: &Suite, s: &NamedScene) -> anyhow::Result<(Vec<Series>, f64)> {
    let walk = street_walk(&s.scene, su.from_point_walk_frames, su.seed + 1, 60.0);
    let region = create(PVS_METHOD, s.scene.clone(), &MethodOptions::default())?;
    let cs = Arc::new(CullScene::new(&s.scene));
    let hzb = method("hzb", cs.clone())?;
    let mut pvs_cache: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
    let (mut first, mut second, mut alone, mut removed) = (vec![], vec![], vec![], vec![]);
    for (k, pf) in walk.iter().enumerate() {
        let f = frustum_of(pf, su.from_point_size)?;
        let key = (
            (f.eye.x / PVS_CELL_M).floor() as i64,
            (f.eye.y / PVS_CELL_M).floor() as i64,
        );
        let pvs = match pvs_cache.entry(key) {
            Entry::Occupied(e) => e.into_mut(),
            Entry::Vacant(e) => {
                let (x0, y0) = (key.0 as f64 * PVS_CELL_M, key.1 as f64 * PVS_CELL_M);
                let cell = ViewCell::new(
                    DVec3::new(x0, y0, 1.5),
                    DVec3::new(x0 + PVS_CELL_M, y0 + PVS_CELL_M, 2.0),
                )?;
                e.insert(region.pvs(&cell)?)
            }
        };
        let fr = hzb.cull(&f, Some(pvs));
        let x = k as f64;
        first.push((x, pvs.len() as f64));
        second.push((x, fr.visible.len() as f64));
        alone.push((x, hzb.cull(&f, None).visible.len() as f64));
        removed.push(fr.culled_pct());
    }
    let series = vec![
        Series {
            name: format!("PVS only ({PVS_METHOD}, {PVS_CELL_M} m cells)"),
            points: first,
        },
        Series {
            name: "PVS + from-point (hzb)".into(),
            points: second,
        },
        Series {
            name: "from-point only (hzb)".into(),
            points: alone,
        },
    ];
    Ok((series, median(&removed)))
}

/// The section, on `scenes` (the suite's city and the scenes given) and the suite's
/// metropolis; each scene's figures go to `records` as they are measured.
pub fn from_point(
    ctx: &mut BenchContext<'_>,
    records: &mut Vec<FromPointRecord>,
    scenes: &[NamedScene],
    rep: &mut Report,
    out: &Path,
) -> anyhow::Result<()> {
    let n = ctx.suite.metropolis_buildings;
    let metropolis = NamedScene {
        name: format!("metropolis-{n}"),
        scene: Arc::new(sightline_scene::generate::metropolis(ctx.suite.seed, n)),
    };
    let mut all: Vec<&NamedScene> = scenes.iter().collect();
    let mut added = Vec::new();
    for p in &ctx.suite.from_point_scenes {
        let p = Path::new(p);
        let name = p.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
        if !p.exists() || scenes.iter().any(|s| s.name == name) {
            continue;
        }
        match sightline_scene::import::load(p, &Default::default()) {
            Ok(sc) => added.push(NamedScene {
                name: name.to_string(),
                scene: Arc::new(sc),
            }),
            Err(e) => ctx.notes.push(format!("cannot load {}: {e}", p.display())),
        }
    }
    all.extend(added.iter());
    all.push(&metropolis);
    let (w, h) = ctx.suite.from_point_size;
    rep.section("From-point culling (hzb, hom, cplp)");
    rep.para(&format!(
        "Street-level walks ({} frames per scene, {w}×{h}, 60° vertical field of view, one thread). Occluder rasterization: every front face of every occluder prism in the frustum, drawn by the masked tile rasterizer of `hzb` (scalar path, SIMD path `{}` chosen at run time; the two give identical buffers) and by the full-resolution inner-union rasterizer of `sightline-raster` (every {}th frame), same faces, same run; rates are medians over frames and include clipping and projection. Culled %: share of all objects culled (frustum and occlusion). `hzb` vs full-res: objects `hzb` hides by occlusion over those a full-resolution depth buffer of the same occluders hides, same frames. False culls: objects the item-buffer truth sees from the eye and a culler hid (every {}th frame); they must be 0.",
        ctx.suite.from_point_frames,
        RasterPath::Simd.describe(),
        ctx.suite.from_point_full_every,
        ctx.suite.from_point_truth_every,
    ));
    let mut raster = Table::new(&[
        "scene",
        "objects",
        "occluder tris/frame",
        "scalar M tris/s",
        "SIMD M tris/s",
        "SIMD / scalar",
        "full-res rasterizer M tris/s",
        "hzb vs full-res depth buffer %",
    ]);
    let mut methods = Table::new(&[
        "scene",
        "method",
        "culled %",
        "median ms",
        "p90 ms",
        "false culls / truth frames",
    ]);
    for s in all.iter().copied() {
        ctx.log(&format!("from-point on {}", s.name));
        let r = match measure_scene(ctx.suite, s) {
            Ok(r) => r,
            Err(e) => {
                ctx.notes
                    .push(format!("from-point culling skipped on {}: {e}", s.name));
                continue;
            }
        };
        raster.row(vec![
            r.scene.clone(),
            r.objects.to_string(),
            format!("{:.0}", r.tris_per_frame),
            m(r.scalar_tris_per_s),
            m(r.simd_tris_per_s),
            format!("{:.2}", r.simd_tris_per_s / r.scalar_tris_per_s.max(1e-9)),
            m(r.full_res_tris_per_s),
            format!("{:.1}", r.hzb_vs_full_res_pct),
        ]);
        for c in &r.cullers {
            methods.row(vec![
                r.scene.clone(),
                c.method.clone(),
                format!("{:.1}", c.culled_pct),
                format!("{:.2}", c.median_ms),
                format!("{:.2}", c.p90_ms),
                format!("{} / {}", c.false_culls, c.truth_frames),
            ]);
            if c.false_culls > 0 {
                ctx.notes.push(format!(
                    "{} had {} false culls on {} — a bug",
                    c.method, c.false_culls, r.scene
                ));
            }
        }
        records.push(r);
    }
    rep.table(&raster);
    rep.table(&methods);
    // The walk plot on the first real scene (Lyon by default), else the generated city.
    let s = all
        .iter()
        .copied()
        .find(|s| s.name.contains("lyon"))
        .unwrap_or(scenes.get(1).unwrap_or(&scenes[0]));
    ctx.log(&format!("from-point walk plot on {}", s.name));
    match walk_plot(ctx.suite, s) {
        Ok((series, removed)) => {
            line_chart(
                &out.join("walk-visible.png"),
                &format!("Visible objects along a walk ({})", s.name),
                "frame",
                "objects",
                &series,
                Scale::Linear,
                Scale::Linear,
            )?;
            rep.para(&format!(
                "Walk plot on {} ({} frames, 3 m apart): the first level is the PVS of the eye's {PVS_CELL_M} m cell by `{PVS_METHOD}` (z 1.5–2 m), the second `hzb` from the eye inside it; the second level removes a median {removed:.1} % of the PVS.",
                s.name,
                ctx.suite.from_point_walk_frames
            ));
            rep.image("walk-visible.png", "visible objects along a walk");
        }
        Err(e) => ctx
            .notes
            .push(format!("walk plot skipped on {}: {e}", s.name)),
    }
    Ok(())
}

//! `sightline map`: a top-down PNG of the scene with one cell's PVS classified against
//! the ground truth, in the manner of Figures 1 and 6 of the dual ray space paper:
//! visible (in the PVS and seen) blue, in the PVS but not seen orange, culled grey,
//! missed (seen but not in the PVS: a bug of a conservative method) magenta, the
//! viewcell green; with a scale bar and a legend.

use crate::cli::Command;
use crate::common::{load_scene, write_atomic};
use anyhow::{bail, Context};
use plotters::prelude::*;
use sightline_core::check::{TruthOptions, TruthScene};
use sightline_geom::{DVec2, Polygon, ViewCell};
use sightline_methods::{create, MethodOptions};
use sightline_scene::{Geometry, Scene};
use std::sync::Arc;

/// Longest image side (pixels).
const MAX_SIDE_PX: u32 = 1400;
const MARGIN_PX: f64 = 20.0;
const LEGEND_PX: u32 = 150;

const BLUE: RGBColor = RGBColor(40, 90, 200);
const ORANGE: RGBColor = RGBColor(245, 150, 30);
const GREY: RGBColor = RGBColor(185, 185, 185);
const MAGENTA: RGBColor = RGBColor(230, 20, 210);
const GREEN: RGBColor = RGBColor(20, 170, 40);
const BACKGROUND: RGBColor = RGBColor(255, 255, 255);

/// Classes of an object for one cell.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Class {
    Visible,
    PvsNotSeen,
    Hidden,
    Missed,
}

impl Class {
    fn color(self) -> RGBColor {
        match self {
            Class::Visible => BLUE,
            Class::PvsNotSeen => ORANGE,
            Class::Hidden => GREY,
            Class::Missed => MAGENTA,
        }
    }
}

fn footprints(scene: &Scene, id: usize) -> Vec<&Polygon> {
    let o = &scene.objects[id];
    match &o.geometry {
        Geometry::Blocks(ps) => ps.iter().map(|p| &p.footprint).collect(),
        Geometry::Flat(ps) => ps.iter().collect(),
        Geometry::Mesh(_) => o.outer.iter().map(|p| &p.footprint).collect(),
    }
}

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Map {
        scene,
        cell,
        at,
        method,
        pvs,
        out,
    } = cmd
    else {
        bail!("internal: `map` called with another command");
    };
    let kind = sightline_world::kind_of(&scene.scene);
    if kind == sightline_world::SceneKind::Bsp {
        let m = sightline_world::resolve(kind, &scene.scene, method.as_deref())?;
        let Some(mode) = sightline_world::portal_mode(m) else {
            bail!("map of a BSP level takes --method portals or portals-fast, not {m}");
        };
        let Some(at) = at else {
            bail!("map of a BSP level takes --at X,Y,Z (the leaf holding the point)");
        };
        if let Some(file) = pvs {
            bail!(
                "map of a BSP level computes the PVS; --pvs {} is not read",
                file.display()
            );
        }
        return super::bsp_map::run(&scene.scene, mode, at, &out, quiet);
    }
    let Some(cell) = cell else {
        bail!("--at X,Y,Z belongs to BSP levels (.bsp); give --cell X0,Y0,Z0,X1,Y1,Z1");
    };
    if let Some(file) = pvs {
        bail!(
            "reading a .pvs file ({}) is not supported by this build yet; use --method NAME",
            file.display()
        );
    }
    let sc = Arc::new(load_scene(&scene)?);
    if sc.objects.is_empty() {
        bail!("the scene is empty");
    }
    let ts = TruthScene::new(&sc);
    let truth = ts.ground_truth(&cell, &TruthOptions::default());
    if truth.samples_used == 0 {
        bail!("viewcell {cell} has no free space (it lies inside a building or below the ground)");
    }
    let pvs: Option<Vec<u32>> = match &method {
        Some(name) => {
            let m = create(name, sc.clone(), &MethodOptions::default())?;
            let mut p = m.pvs(&cell)?;
            p.sort_unstable();
            Some(p)
        }
        None => None,
    };
    let labelled = method.as_deref().zip(pvs.as_deref());
    let png = map_png(&sc, &cell, &truth.visible, labelled)?;
    write_atomic(&out, &png)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// The PNG map of `cell`: the objects of `visible` (the ground truth, sorted) and, with
/// a method's name and sorted PVS, each object classified against it (`map`, `demo`).
pub(crate) fn map_png(
    sc: &Scene,
    cell: &ViewCell,
    visible: &[u32],
    pvs: Option<(&str, &[u32])>,
) -> anyhow::Result<Vec<u8>> {
    let classes: Vec<Class> = (0..sc.objects.len() as u32)
        .map(|id| {
            let seen = visible.binary_search(&id).is_ok();
            let listed = pvs.map_or(seen, |(_, p)| p.binary_search(&id).is_ok());
            match (listed, seen) {
                (true, true) => Class::Visible,
                (true, false) => Class::PvsNotSeen,
                (false, false) => Class::Hidden,
                (false, true) => Class::Missed,
            }
        })
        .collect();
    let title = match pvs {
        Some((m, p)) => format!(
            "{m}, cell {cell}: PVS {} / VS {} / {} objects, missed {}",
            p.len(),
            visible.len(),
            sc.objects.len(),
            classes.iter().filter(|c| **c == Class::Missed).count()
        ),
        None => format!(
            "ground truth, cell {cell}: VS {} / {} objects",
            visible.len(),
            sc.objects.len()
        ),
    };
    render(sc, cell, &classes, &title, pvs.is_some())
}

/// Draw the map and encode it as PNG.
fn render(
    scene: &Scene,
    cell: &ViewCell,
    classes: &[Class],
    title: &str,
    with_pvs: bool,
) -> anyhow::Result<Vec<u8>> {
    let b = scene.bounds.xy().union(cell.aabb().xy());
    let size = b.size().max(DVec2::splat(1.0));
    let scale = (MAX_SIDE_PX as f64 - 2.0 * MARGIN_PX) / size.x.max(size.y);
    let w = (size.x * scale + 2.0 * MARGIN_PX).ceil() as u32;
    let h = (size.y * scale + 2.0 * MARGIN_PX).ceil() as u32 + LEGEND_PX;
    let to_px = |p: DVec2| -> (i32, i32) {
        (
            (MARGIN_PX + (p.x - b.min.x) * scale).round() as i32,
            (MARGIN_PX + (b.max.y - p.y) * scale).round() as i32,
        )
    };
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&BACKGROUND).context("drawing the map")?;
        // Ground surfaces (flat objects: streets, squares, parks) first and translucent,
        // so they never veil a building; then objects with holes (courtyards), so what
        // stands in a courtyard stays on top; then by class so the interesting classes
        // are drawn last.
        let mut order: Vec<usize> = (0..scene.objects.len()).collect();
        let rank = |c: Class| match c {
            Class::Hidden => 0,
            Class::PvsNotSeen => 1,
            Class::Visible => 2,
            Class::Missed => 3,
        };
        let is_flat = |id: usize| matches!(scene.objects[id].geometry, Geometry::Flat(_));
        order.sort_by_key(|&id| {
            let holes = footprints(scene, id).iter().any(|p| !p.holes.is_empty());
            (!is_flat(id), !holes, rank(classes[id]))
        });
        let any_flat = (0..scene.objects.len()).any(is_flat);
        for id in order {
            let flat = matches!(scene.objects[id].geometry, Geometry::Flat(_));
            let c = classes[id].color();
            let fill = if flat { c.mix(0.35) } else { c.mix(1.0) };
            for fp in footprints(scene, id) {
                let ext: Vec<(i32, i32)> = fp.exterior.iter().map(|p| to_px(*p)).collect();
                root.draw(&plotters::element::Polygon::new(ext.clone(), fill.filled()))
                    .context("drawing the map")?;
                for hole in &fp.holes {
                    let hp: Vec<(i32, i32)> = hole.iter().map(|p| to_px(*p)).collect();
                    root.draw(&plotters::element::Polygon::new(hp, BACKGROUND.filled()))
                        .context("drawing the map")?;
                }
                let mut outline = ext;
                outline.push(outline[0]);
                root.draw(&PathElement::new(outline, RGBColor(60, 60, 60).mix(0.5)))
                    .context("drawing the map")?;
            }
        }
        // The viewcell, at least 5 px wide so it shows at city scale.
        let (c0, c1) = (to_px(cell.min.truncate()), to_px(cell.max.truncate()));
        let cx = (c0.0 + c1.0) / 2;
        let cy = (c0.1 + c1.1) / 2;
        let hw = ((c1.0 - c0.0).abs() / 2).max(3);
        let hh = ((c1.1 - c0.1).abs() / 2).max(3);
        root.draw(&Rectangle::new(
            [(cx - hw, cy - hh), (cx + hw, cy + hh)],
            GREEN.filled(),
        ))
        .context("drawing the map")?;
        root.draw(&Rectangle::new(
            [(cx - hw - 6, cy - hh - 6), (cx + hw + 6, cy + hh + 6)],
            GREEN.stroke_width(2),
        ))
        .context("drawing the map")?;
        // Legend and scale bar below the map.
        let y0 = (h - LEGEND_PX) as i32 + 10;
        let font = ("sans-serif", 18).into_font();
        root.draw(&Text::new(title.to_string(), (20, y0), font.clone()))
            .context("drawing the map")?;
        let mut entries = vec![(
            BLUE,
            if with_pvs {
                "visible (in PVS, seen)"
            } else {
                "visible (seen)"
            },
        )];
        if with_pvs {
            entries.push((ORANGE, "in PVS, not seen"));
        }
        entries.push((
            GREY,
            if with_pvs {
                "culled (hidden)"
            } else {
                "not seen"
            },
        ));
        if with_pvs {
            entries.push((MAGENTA, "MISSED (seen, not in PVS)"));
        }
        entries.push((GREEN, "viewcell"));
        if any_flat {
            // Grey at 35 % over the white background, as drawn.
            entries.push((RGBColor(230, 230, 230), "pale: ground surfaces"));
        }
        let ly = y0 + 40;
        draw_legend(&root, &entries, ly, &font)?;
        // Scale bar: a round length of about a fifth of the width.
        let target_m = size.x.max(size.y) / 5.0;
        let step = 10f64.powf(target_m.log10().floor());
        let bar_m = [1.0, 2.0, 5.0]
            .iter()
            .map(|k| k * step)
            .filter(|l| *l <= target_m)
            .fold(step, f64::max);
        let bar_px = (bar_m * scale).round() as i32;
        let by = y0 + 95;
        root.draw(&Rectangle::new(
            [(20, by), (20 + bar_px, by + 8)],
            BLACK.filled(),
        ))
        .context("drawing the map")?;
        for k in 0..=4 {
            let xk = 20 + bar_px * k / 4;
            root.draw(&PathElement::new(vec![(xk, by - 5), (xk, by + 8)], BLACK))
                .context("drawing the map")?;
        }
        root.draw(&Text::new(
            format!("{bar_m} m"),
            (30 + bar_px, by - 5),
            font.clone(),
        ))
        .context("drawing the map")?;
        root.present().context("drawing the map")?;
    }
    encode_png(w, h, buf)
}

/// A legend row at height `y`: a filled square and a label per entry, left to right.
pub(crate) fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    entries: &[(RGBColor, &str)],
    y: i32,
    font: &FontDesc,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let mut x = 20;
    for &(c, label) in entries {
        root.draw(&Rectangle::new([(x, y), (x + 22, y + 22)], c.filled()))
            .context("drawing the map")?;
        root.draw(&Text::new(label.to_string(), (x + 30, y + 2), font.clone()))
            .context("drawing the map")?;
        x += 40 + 10 * label.len() as i32;
    }
    Ok(())
}

/// An RGB buffer of `w` × `h` as PNG bytes.
pub(crate) fn encode_png(w: u32, h: u32, buf: Vec<u8>) -> anyhow::Result<Vec<u8>> {
    let img = image::RgbImage::from_raw(w, h, buf).context("map buffer size")?;
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .context("encoding the PNG")?;
    Ok(png)
}

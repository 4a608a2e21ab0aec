//! `sightline map LEVEL.bsp --at X,Y,Z --method portals|portals-fast -o map.png`: a plan
//! (top view) of a Quake level with the PVS of the leaf holding a point. Floors (faces
//! whose front looks up) are filled, walls drawn as their top-view segments, ceilings
//! left out (they would hide the floors); what the PVS keeps is in colour, the rest
//! grey; the source leaf is outlined in green with the point marked.

use crate::common::write_atomic;
use anyhow::Context;
use plotters::prelude::*;
use sightline_portals::{Mode, PortalMethod, Portals};
use sightline_scene::import::bsp::{load_bsp, BspLevel};
use std::path::Path;

const MAX_SIDE_PX: u32 = 1400;
const MARGIN_PX: f64 = 20.0;
const LEGEND_PX: u32 = 130;

pub(crate) const VISIBLE_FLOOR: RGBColor = RGBColor(40, 90, 200);
pub(crate) const HIDDEN_FLOOR: RGBColor = RGBColor(215, 215, 215);
const VISIBLE_WALL: RGBColor = RGBColor(245, 150, 30);
const HIDDEN_WALL: RGBColor = RGBColor(150, 150, 150);
const SOURCE: RGBColor = RGBColor(20, 170, 40);

/// A face's front normal's z above this makes it a floor, below minus it a ceiling.
const FLOOR_NZ: f64 = 0.3;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Floor,
    Wall,
    Ceiling,
}

fn kind(level: &BspLevel, face: usize) -> Kind {
    let f = &level.faces[face];
    let nz = level
        .planes
        .get(f.plane as usize)
        .map_or(0.0, |p| p.normal[2]);
    let nz = if f.back { -nz } else { nz };
    if nz > FLOOR_NZ {
        Kind::Floor
    } else if nz < -FLOOR_NZ {
        Kind::Ceiling
    } else {
        Kind::Wall
    }
}

/// `map LEVEL.bsp --at X,Y,Z`: compute the leaf's PVS and write the plan.
pub fn run(path: &Path, mode: Mode, at: [f64; 3], out: &Path, quiet: bool) -> anyhow::Result<()> {
    let level = load_bsp(path).with_context(|| format!("cannot load {}", path.display()))?;
    let leaf = level.point_leaf(at);
    if !level.is_view_leaf(leaf) {
        anyhow::bail!(
            "point {},{},{} is not in open space (leaf {leaf} is solid, sky or outside the level)",
            at[0],
            at[1],
            at[2]
        );
    }
    let portals = Portals::build(&level).context("cannot build the level's portals")?;
    let m = PortalMethod::new(portals, mode);
    let pvs = m.leaf_pvs(leaf);
    let name = match mode {
        Mode::Full => "portals",
        Mode::Fast => "portals-fast",
    };
    let title = format!(
        "{name}, leaf {leaf} at {},{},{}: {} of {} faces, {} of {} leaves potentially visible",
        at[0],
        at[1],
        at[2],
        pvs.faces.len(),
        level.faces.len(),
        pvs.leaves.len(),
        level.visleafs
    );
    let png = plan_png(&level, leaf, at, &pvs.faces, &title)?;
    write_atomic(out, &png)?;
    if !quiet {
        println!("wrote {}: {title}", out.display());
    }
    Ok(())
}

/// The plan of `level` with `visible` (sorted face ids) in colour, as PNG bytes.
pub(crate) fn plan_png(
    level: &BspLevel,
    leaf: u32,
    at: [f64; 3],
    visible: &[u32],
    title: &str,
) -> anyhow::Result<Vec<u8>> {
    let (lo, hi) = (level.bounds.min, level.bounds.max);
    let (sx, sy) = ((hi.x - lo.x).max(1.0), (hi.y - lo.y).max(1.0));
    let scale = (MAX_SIDE_PX as f64 - 2.0 * MARGIN_PX) / sx.max(sy);
    let w = (sx * scale + 2.0 * MARGIN_PX).ceil() as u32;
    let h = ((sy * scale + 2.0 * MARGIN_PX).ceil() as u32 + LEGEND_PX).max(LEGEND_PX + 40);
    let w = w.max(900);
    let to_px = |x: f64, y: f64| -> (i32, i32) {
        (
            (MARGIN_PX + (x - lo.x) * scale).round() as i32,
            (MARGIN_PX + (hi.y - y) * scale).round() as i32,
        )
    };
    // Hidden first, then visible; within each, lower faces first (upper floors on top).
    let mut order: Vec<(bool, f64, usize)> = (0..level.faces.len())
        .filter(|&f| kind(level, f) != Kind::Ceiling && level.faces[f].polygon.len() >= 2)
        .map(|f| {
            let z = level.faces[f]
                .polygon
                .iter()
                .map(|p| p[2])
                .fold(f64::MIN, f64::max);
            (visible.binary_search(&(f as u32)).is_ok(), z, f)
        })
        .collect();
    order.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).context("drawing the map")?;
        for (seen, _, f) in order {
            let pts: Vec<(i32, i32)> = level.faces[f]
                .polygon
                .iter()
                .map(|p| to_px(p[0], p[1]))
                .collect();
            match (kind(level, f), seen) {
                (Kind::Floor, seen) => {
                    let c = if seen { VISIBLE_FLOOR } else { HIDDEN_FLOOR };
                    root.draw(&plotters::element::Polygon::new(pts, c.filled()))
                        .context("drawing the map")?;
                }
                (_, seen) => {
                    let c = if seen { VISIBLE_WALL } else { HIDDEN_WALL };
                    let mut outline = pts;
                    outline.push(outline[0]);
                    root.draw(&PathElement::new(outline, c.stroke_width(2)))
                        .context("drawing the map")?;
                }
            }
        }
        if let Some(l) = level.leaves.get(leaf as usize) {
            let (a, b) = (to_px(l.mins[0], l.maxs[1]), to_px(l.maxs[0], l.mins[1]));
            root.draw(&Rectangle::new([a, b], SOURCE.stroke_width(3)))
                .context("drawing the map")?;
        }
        root.draw(&Circle::new(to_px(at[0], at[1]), 6, SOURCE.filled()))
            .context("drawing the map")?;
        let y0 = (h - LEGEND_PX) as i32 + 10;
        let font = ("sans-serif", 18).into_font();
        root.draw(&Text::new(title.to_string(), (20, y0), font.clone()))
            .context("drawing the map")?;
        let entries = [
            (VISIBLE_FLOOR, "floor in the PVS"),
            (HIDDEN_FLOOR, "floor culled"),
            (VISIBLE_WALL, "wall in the PVS"),
            (HIDDEN_WALL, "wall culled"),
            (SOURCE, "source leaf and point"),
        ];
        let ly = y0 + 40;
        super::map::draw_legend(&root, &entries, ly, &font)?;
        root.draw(&Text::new(
            "top view; ceilings left out".to_string(),
            (20, ly + 40),
            font,
        ))
        .context("drawing the map")?;
        root.present().context("drawing the map")?;
    }
    super::map::encode_png(w, h, buf)
}

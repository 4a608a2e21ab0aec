//! Debug dump of the extended depth maps of one cell (run in release):
//! `cargo run --release -p sightline-methods --example ext_proj_debug -- SCENE x0 y0 z0 x1 y1 z1 OUTDIR`
//!
//! Writes one PPM per projection plane (`OUTDIR/<dir>_<k>.ppm`): covered pixels in
//! grey (darker = nearer), uncovered in black, and the Projection rectangles of the
//! occludees outlined (green when hidden on that plane, red otherwise). Prints the
//! plane positions, the covered fraction and the number of occludees hidden per plane.
//!
//! `ext_proj_debug SCENE CELLS.json` instead prints the mean PVS and the median time
//! per cell of a cells.json. Environment overrides of the parameters: EXTPROJ_RES, EXTPROJ_MAXOCC,
//! EXTPROJ_CANDS, EXTPROJ_PPD, EXTPROJ_SPLITS, EXTPROJ_IMPROVED (0/1), EXTPROJ_BUDGET,
//! EXTPROJ_MINM; EXTPROJ_AT, EXTPROJ_OBJ and EXTPROJ_PT select planes, report on one
//! object, or list the pieces covering one plane point (see the code).

use sightline_geom::{DVec3, ViewCell};
use sightline_methods::ext_proj::extended_projection;
use sightline_methods::ext_proj::occludee_projection;
use sightline_methods::ext_proj::pixel_range;
use sightline_methods::ext_proj::{adaptive_pvs, ExtProj, Params, PlaneMap};
use sightline_methods::ext_proj::{Direction, Plane};
use sightline_scene::import;
use std::sync::Arc;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<usize>().ok());
    let mut params = Params::default();
    if let Some(m) = env("EXTPROJ_MAXOCC") {
        params.max_occluders = m;
    }
    if let Some(m) = env("EXTPROJ_CANDS") {
        params.plane_candidates = m;
    }
    if let Some(m) = env("EXTPROJ_PPD") {
        params.planes_per_direction = m;
    }
    if let Some(m) = env("EXTPROJ_SPLITS") {
        params.occludee_splits = m as u32;
    }
    if let Some(m) = env("EXTPROJ_RES") {
        params.resolution_px = m.clamp(8, 4096).next_power_of_two();
    }
    if let Some(m) = env("EXTPROJ_IMPROVED") {
        params.improved = m != 0;
    }
    if let Some(m) = env("EXTPROJ_BUDGET") {
        params.adaptive_budget = Some(m);
    }
    if let Some(m) = env("EXTPROJ_MINM") {
        params.adaptive_min_m = m as f64;
    }
    // `ext_proj_debug SCENE CELLS.json`: mean PVS and time per cell of those cells.
    if a.len() == 2 {
        let scene = match import::load(std::path::Path::new(&a[0]), &Default::default()) {
            Ok(s) => Arc::new(s),
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        };
        let text = std::fs::read_to_string(&a[1]).unwrap_or_default();
        let cells: Vec<[f64; 6]> = parse_cells(&text);
        let ext = ExtProj::new(scene.clone(), params);
        let all: Vec<u32> = (0..scene.objects.len() as u32).collect();
        let mut sizes = Vec::new();
        let mut ms = Vec::new();
        for c in &cells {
            let Ok(cell) =
                ViewCell::new(DVec3::new(c[0], c[1], c[2]), DVec3::new(c[3], c[4], c[5]))
            else {
                continue;
            };
            let t = std::time::Instant::now();
            sizes.push(match ext.params.adaptive_budget {
                Some(b) => adaptive_pvs(&ext, &cell, &all, b).len(),
                None => ext.pvs_among(&cell, &all).len(),
            });
            ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
        ms.sort_by(f64::total_cmp);
        let mean = sizes.iter().sum::<usize>() as f64 / sizes.len().max(1) as f64;
        println!(
            "{} cells: mean PVS {mean:.1} of {}, median {:.0} ms/cell; sizes {sizes:?}",
            sizes.len(),
            scene.objects.len(),
            ms.get(ms.len() / 2).copied().unwrap_or(0.0)
        );
        return;
    }
    if a.len() < 8 {
        eprintln!("usage: ext_proj_debug SCENE x0 y0 z0 x1 y1 z1 OUTDIR");
        std::process::exit(2);
    }
    let v: Vec<f64> = a[1..7]
        .iter()
        .map(|s| s.parse().unwrap_or(f64::NAN))
        .collect();
    let Ok(cell) = ViewCell::new(DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5])) else {
        eprintln!("bad cell");
        std::process::exit(2);
    };
    let scene = match import::load(std::path::Path::new(&a[0]), &Default::default()) {
        Ok(s) => Arc::new(s),
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let out = std::path::PathBuf::from(&a[7]);
    let _ = std::fs::create_dir_all(&out);
    let ext = ExtProj::new(scene.clone(), params);
    let t = std::time::Instant::now();
    let ids = ext.occluders.relevant(&cell.aabb());
    for dir in Direction::ALL {
        println!(
            "{}: {} relevant pieces, {} selected",
            dir.name(),
            ids.len(),
            ext.local_pieces(&cell, dir, &ids).len()
        );
    }
    let pvs = ext.pvs_among(&cell, &(0..scene.objects.len() as u32).collect::<Vec<_>>());
    println!(
        "pvs {} in {:.0} ms",
        pvs.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    // EXTPROJ_AT="10,40,80": planes at these distances beyond the cell's far face
    // in every horizontal direction instead of the chosen ones.
    let maps = match std::env::var("EXTPROJ_AT") {
        Ok(list) => {
            let ids = ext.occluders.relevant(&cell.aabb());
            let mut maps = Vec::new();
            for dir in Direction::ALL.into_iter().filter(|d| !d.is_vertical()) {
                let lc = dir.box_to_local(cell.min, cell.max);
                let pieces = ext.local_pieces(&cell, dir, &ids);
                for d in list.split(',').filter_map(|s| s.parse::<f64>().ok()) {
                    let plane = Plane::new(
                        dir,
                        &lc,
                        lc.max.x + d,
                        ext.params.resolution_px,
                        ext.params.extension,
                    );
                    let map = ext.depth_map(&plane, &lc, &pieces);
                    maps.push(PlaneMap {
                        plane,
                        cell: lc,
                        map,
                    });
                }
            }
            maps
        }
        Err(_) => ext.plane_maps(&cell),
    };
    let boxes: Vec<_> = scene.objects.iter().map(|o| o.bounds).collect();
    let pvs = ext.pvs_among(&cell, &(0..scene.objects.len() as u32).collect::<Vec<_>>());
    println!(
        "{} objects, {} occluder pieces, PVS {}",
        scene.objects.len(),
        ext.occluders.pieces.len(),
        pvs.len()
    );
    if let Some(id) = std::env::var("EXTPROJ_OBJ")
        .ok()
        .and_then(|s| s.parse::<usize>().ok())
    {
        let o = &scene.objects[id];
        println!("object {id}: bounds {:?}..{:?}", o.bounds.min, o.bounds.max);
        for b in o.outer.iter().map(|p| p.aabb()) {
            for m in &maps {
                if m.hides(&b, true) {
                    println!(
                        "  part {:?}..{:?} hidden on {} x={:.2}",
                        b.min,
                        b.max,
                        m.plane.dir.name(),
                        m.plane.x
                    );
                }
            }
        }
        for m in &maps {
            let occ = m.plane.dir.box_to_local(o.bounds.min, o.bounds.max);
            let pr = occludee_projection(&m.cell, &occ, m.plane.x, true);
            println!(
                "  {} x={:.2}: hides {} local {:?}..{:?} proj {:?}",
                m.plane.dir.name(),
                m.plane.x,
                m.hides(&o.bounds, true),
                occ.min,
                occ.max,
                pr
            );
        }
    }
    // EXTPROJ_PT="k,x,u,v": the occluder pieces whose Projection or slice on the plane
    // w = x of direction k (index in Direction::ALL) contains the point (u, v).
    if let Ok(pt) = std::env::var("EXTPROJ_PT") {
        let f: Vec<f64> = pt.split(',').filter_map(|s| s.parse().ok()).collect();
        if f.len() == 4 {
            let dir = Direction::ALL[f[0] as usize];
            let (x, q) = (f[1], sightline_geom::DVec2::new(f[2], f[3]));
            let lc = dir.box_to_local(cell.min, cell.max);
            let ids = ext.occluders.relevant(&cell.aabb());
            let inside = |poly: &[sightline_geom::DVec2]| {
                (0..poly.len()).all(|i| {
                    let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                    (b - a).perp_dot(q - a) >= 0.0
                })
            };
            for p in ext.local_pieces(&cell, dir, &ids) {
                let piece = &ext.occluders.pieces[p.index as usize];
                if let Some((poly, d)) = extended_projection(&p.vertices, &lc, x) {
                    if inside(&poly) {
                        println!(
                            "  piece {} projection depth {d:.2} bounds {:?}..{:?} {:?}",
                            p.index, piece.bounds.min, piece.bounds.max, piece.occluder
                        );
                    }
                }
                if p.near < x && x < p.far {
                    if let Some(sl) = piece.occluder.slice(dir, x) {
                        if inside(&sl) {
                            println!(
                                "  piece {} slice {:?} bounds {:?}..{:?}",
                                p.index, sl, piece.bounds.min, piece.bounds.max
                            );
                        }
                    }
                }
            }
        }
    }
    let mut count: std::collections::HashMap<&str, usize> = Default::default();
    for m in &maps {
        let n = m.map.n;
        let k = count.entry(m.plane.dir.name()).or_default();
        let name = format!(
            "{}_{}",
            m.plane.dir.name().replace('+', "p").replace('-', "m"),
            k
        );
        *k += 1;
        let mut img = vec![[0u8; 3]; n * n];
        let mut dmax = 0.0f32;
        for j in 0..n {
            for i in 0..n {
                let d = m.map.at(i, j);
                if d.is_finite() {
                    dmax = dmax.max(d.abs());
                }
            }
        }
        for j in 0..n {
            for i in 0..n {
                let d = m.map.at(i, j);
                if d.is_finite() {
                    let g = 90 + (165.0 * (1.0 - d.abs() / dmax.max(1e-6))) as u8;
                    img[j * n + i] = [g, g, g];
                }
            }
        }
        let mut hidden = 0;
        let mut tested = 0;
        for b in &boxes {
            let occ = m.plane.dir.box_to_local(b.min, b.max);
            let Some((rect, _)) = occludee_projection(&m.cell, &occ, m.plane.x, true) else {
                continue;
            };
            let (lo, hi) = (m.plane.to_px(rect.min), m.plane.to_px(rect.max));
            let Some(r) = pixel_range(lo, hi, n) else {
                continue;
            };
            tested += 1;
            let h = m.hides(b, true);
            hidden += h as usize;
            let c = if h { [0, 255, 0] } else { [255, 0, 0] };
            for i in r[0]..=r[2] {
                img[r[1] * n + i] = c;
                img[r[3] * n + i] = c;
            }
            for j in r[1]..=r[3] {
                img[j * n + r[0]] = c;
                img[j * n + r[2]] = c;
            }
        }
        println!(
            "{name}: x = {:.1} (cell far face {:.1}), rect {:.0}×{:.0} m, covered {:.1} %, occludees in map {tested}, hidden {hidden}",
            m.plane.x,
            m.cell.max.x,
            m.plane.rect.size().x,
            m.plane.rect.size().y,
            100.0 * m.map.covered() as f64 / (n * n) as f64
        );
        // Row 0 at the bottom (v up), each pixel doubled.
        let s = 2 * n;
        let mut rgb = Vec::with_capacity(s * s * 3);
        for j in (0..s).rev() {
            for i in 0..s {
                rgb.extend_from_slice(&img[(j / 2) * n + i / 2]);
            }
        }
        let path = out.join(format!("{name}.png"));
        if let Err(e) = std::fs::write(&path, png(s, s, &rgb)) {
            eprintln!("{}: {e}", path.display());
        }
    }
}

/// A minimal PNG encoder (RGB, stored deflate blocks): no image dependency needed.
fn png(w: usize, h: usize, rgb: &[u8]) -> Vec<u8> {
    fn crc32(data: &[u8]) -> u32 {
        let mut c = 0xffff_ffffu32;
        for &b in data {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xedb8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut c = kind.to_vec();
        c.extend_from_slice(data);
        out.extend_from_slice(&c);
        out.extend_from_slice(&crc32(&c).to_be_bytes());
    }
    let mut raw = Vec::with_capacity((w * 3 + 1) * h);
    for j in 0..h {
        raw.push(0);
        raw.extend_from_slice(&rgb[j * w * 3..(j + 1) * w * 3]);
    }
    let mut z = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = raw.chunks(65535).collect();
    for (k, b) in blocks.iter().enumerate() {
        z.push((k + 1 == blocks.len()) as u8);
        z.extend_from_slice(&(b.len() as u16).to_le_bytes());
        z.extend_from_slice(&(!(b.len() as u16)).to_le_bytes());
        z.extend_from_slice(b);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &x in &raw {
        a = (a + x as u32) % 65521;
        b = (b + a) % 65521;
    }
    z.extend_from_slice(&((b << 16) | a).to_be_bytes());
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&(w as u32).to_be_bytes());
    ihdr.extend_from_slice(&(h as u32).to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(&mut out, b"IDAT", &z);
    chunk(&mut out, b"IEND", &[]);
    out
}

/// The numbers of a cells.json (`[[x0,y0,z0,x1,y1,z1], ...]`), six by six.
fn parse_cells(text: &str) -> Vec<[f64; 6]> {
    let nums: Vec<f64> = text
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e' || c == 'E'))
        .filter_map(|s| s.parse().ok())
        .collect();
    nums.chunks_exact(6)
        .map(|c| [c[0], c[1], c[2], c[3], c[4], c[5]])
        .collect()
}

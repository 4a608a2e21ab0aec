//! The tree's portalization (`portalize.rs`) against qbsp's portal file of the same level:
//! portal counts, total areas, leaf pairs found by one and not the other; with `FLOW=1`
//! also Σ|PVS| of the full flow on each, against the level's own rows.
//!
//! ```text
//! cargo run --release -p sightline-portals --example portalize_compare LEVEL.bsp LEVEL.prt
//! ```
use sightline_portals::flow::{self, Graph};
use sightline_portals::portalize::{self, Portal};
use sightline_portals::prt;
use sightline_scene::import::bsp::load_bsp;
use std::path::Path;
use std::time::Instant;

fn sigma(level: &sightline_scene::import::bsp::BspLevel, portals: &[Portal]) -> (usize, f64) {
    let g = Graph::from_portals(
        level.leaves.len(),
        portals.iter().map(|p| (&p.winding, p.plane, p.leaves)),
    );
    let t = Instant::now();
    let ms = flow::might_see_all(&g);
    let fl = flow::flow_all(&g, &ms);
    let s: usize = (1..=level.visleafs)
        .map(|l| flow::cell_pvs(&g, &fl, l).count())
        .sum();
    (s, t.elapsed().as_secs_f64())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let level = load_bsp(Path::new(&args[0])).unwrap();
    let reference: usize = (1..=level.visleafs)
        .map(|l| level.reference_row(l).len())
        .sum();
    let file = prt::parse_prt(&std::fs::read(&args[1]).unwrap()).unwrap();
    let theirs = prt::portals_for_level(&file, &level).unwrap();
    let ours = portalize::portalize(&level);
    let area = |v: &[Portal]| v.iter().map(|p| p.winding.area()).sum::<f64>();
    println!(
        "portals ours {} (area {:.0}) prt {} (area {:.0})",
        ours.len(),
        area(&ours),
        theirs.len(),
        area(&theirs)
    );
    let pairs = |v: &[Portal]| {
        let mut s: Vec<[u32; 2]> = v
            .iter()
            .map(|p| {
                let mut l = p.leaves;
                l.sort();
                l
            })
            .collect();
        s.sort();
        s.dedup();
        s
    };
    let (po, pt) = (pairs(&ours), pairs(&theirs));
    let only_ours = po.iter().filter(|p| pt.binary_search(p).is_err()).count();
    let only_theirs = pt.iter().filter(|p| po.binary_search(p).is_err()).count();
    println!(
        "leaf pairs ours {} prt {} only ours {only_ours} only prt {only_theirs}",
        po.len(),
        pt.len()
    );
    if std::env::var("FLOW").is_err() {
        return;
    }
    for (name, v) in [("ours", &ours), ("prt", &theirs)] {
        let (s, t) = sigma(&level, v);
        println!(
            "{name}: sigma {s} ratio {:.4} flow {t:.2}s",
            s as f64 / reference as f64
        );
    }
}

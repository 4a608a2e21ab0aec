//! Where our full flow is looser than another tool's rows (issue #49): per leaf, our
//! row against the rows of a reference file (say ericw-tools' `vis` output on the same
//! `.prt`), the worst leaves, and how much of the gap the flows' window of done
//! results (`flow::FLOW_WINDOW`) explains: the same flows run one after the other in
//! the same order, each bounded by the results of *every* earlier flow (window 0, as a
//! one-thread vis does) instead of those 32 places back.
//!
//! ```text
//! cargo run --release -p sightline-portals --example flow_probe LEVEL.bsp LEVEL.prt REFERENCE.bsp [WORST]
//! ```

use sightline_portals::flow::{cell_pvs, flow, flow_waves, Seen, FLOW_WINDOW};
use sightline_portals::oracle::{pair_visible, sample_leaf, Rng};
use sightline_portals::prt::parse_prt;
use sightline_portals::{Mode, Portals};
use sightline_scene::import::bsp::load_bsp;
use std::path::Path;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [bsp, prt, reference, rest @ ..] = &args[..] else {
        eprintln!("usage: flow_probe LEVEL.bsp LEVEL.prt REFERENCE.bsp [WORST]");
        std::process::exit(2);
    };
    let worst: usize = rest.first().and_then(|w| w.parse().ok()).unwrap_or(10);
    let level = load_bsp(Path::new(bsp)).expect("level");
    let reference = load_bsp(Path::new(reference)).expect("reference");
    let file = parse_prt(&std::fs::read(prt).expect("prt")).expect("prt");
    let portals = Portals::from_prt(&level, &file).expect("portals");
    let g = portals.graph();
    let mightsee = portals.portal_sets(Mode::Fast).to_vec();
    let order: Vec<usize> = flow_waves(g, &mightsee).concat();

    // The flows in order, each bounded by the results `window` places back and more.
    let run = |window: usize| -> Vec<Seen> {
        let mut done: Vec<Option<Seen>> = vec![None; g.portals.len()];
        let mut results: Vec<Seen> = Vec::with_capacity(order.len());
        for (i, &p) in order.iter().enumerate() {
            if i > window {
                let j = i - window - 1;
                done[order[j]] = Some(results[j].clone());
            }
            results.push(flow(g, p, &mightsee, &done));
        }
        let mut out: Vec<Option<Seen>> = vec![None; g.portals.len()];
        for (i, &p) in order.iter().enumerate() {
            out[p] = Some(results[i].clone());
        }
        out.into_iter()
            .map(|s| s.expect("every directed portal is in the order"))
            .collect()
    };
    let view: Vec<u32> = (1..=level.visleafs)
        .filter(|&l| level.is_view_leaf(l))
        .collect();
    let rows = |seen: &[Seen]| -> Vec<usize> {
        view.iter().map(|&l| cell_pvs(g, seen, l).count()).collect()
    };
    let t = Instant::now();
    let windowed = run(FLOW_WINDOW);
    let t_w = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let sequential = run(0);
    let t_s = t.elapsed().as_secs_f64();
    let (rw, rs) = (rows(&windowed), rows(&sequential));
    let rr: Vec<usize> = view
        .iter()
        .map(|&l| reference.reference_row(l).len())
        .collect();
    let shipped: Vec<usize> = view.iter().map(|&l| level.reference_row(l).len()).collect();
    let sum = |v: &[usize]| v.iter().sum::<usize>();
    println!(
        "view leaves {}; Σ over view leaves: ours window {FLOW_WINDOW} {} ({t_w:.1} s), ours window 0 {} ({t_s:.1} s), reference {}, shipped {}",
        view.len(),
        sum(&rw),
        sum(&rs),
        sum(&rr),
        sum(&shipped)
    );
    let (over_w, over_s): (usize, usize) = view
        .iter()
        .enumerate()
        .map(|(i, _)| (rw[i].saturating_sub(rr[i]), rs[i].saturating_sub(rr[i])))
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let under: usize = (0..view.len()).map(|i| rr[i].saturating_sub(rw[i])).sum();
    let over_leaves = (0..view.len()).filter(|&i| rw[i] > rr[i]).count();
    println!(
        "leaves where ours > reference: {over_leaves}; Σ excess window {FLOW_WINDOW} {over_w}, window 0 {over_s}; Σ where the reference lists more {under}"
    );
    // Misses of the windowed flow: 60 sources spread evenly, every view leaf their
    // row lacks, 16 segments per pair (the `vis_rows` check).
    let mut rng = Rng::new(49);
    let points: Vec<Vec<[f64; 3]>> = (0..level.leaves.len() as u32)
        .map(|l| sample_leaf(&level, l, 12, &mut rng))
        .collect();
    let (mut sources, mut misses) = (0, 0);
    for &s in view.iter().step_by((view.len() / 60).max(1)) {
        sources += 1;
        let row = cell_pvs(g, &windowed, s);
        for &t in &view {
            if !row.get(t as usize)
                && pair_visible(
                    &level,
                    &points[s as usize],
                    &points[t as usize],
                    16,
                    &mut rng,
                )
            {
                misses += 1;
            }
        }
    }
    println!("oracle: {sources} sources, {misses} misses");
    // The worst leaves, with the oracle on their extra leaves.
    let mut idx: Vec<usize> = (0..view.len()).collect();
    idx.sort_by_key(|&i| std::cmp::Reverse(rw[i] as i64 - rr[i] as i64));
    let mut rng = Rng::new(5);
    println!("leaf | size (x y z) | portals | ours w32 | ours w0 | reference | shipped | extra (ours − ref) | extra with a clear segment (of 64 tries)");
    for &i in idx.iter().take(worst) {
        let l = view[i];
        let leaf = &level.leaves[l as usize];
        let size: Vec<f64> = (0..3).map(|k| leaf.maxs[k] - leaf.mins[k]).collect();
        let ours = cell_pvs(g, &windowed, l);
        let refrow = reference.reference_row(l);
        let extra: Vec<u32> = ours
            .ones()
            .map(|x| x as u32)
            .filter(|x| refrow.binary_search(x).is_err())
            .collect();
        let src = sample_leaf(&level, l, 24, &mut rng);
        let clear = extra
            .iter()
            .filter(|&&x| {
                let dst = sample_leaf(&level, x, 24, &mut rng);
                pair_visible(&level, &src, &dst, 64, &mut rng)
            })
            .count();
        println!(
            "{l} | {:.0} {:.0} {:.0} | {} | {} | {} | {} | {} | {} | {clear}",
            size[0],
            size[1],
            size[2],
            g.leaf_portals[l as usize].len(),
            rw[i],
            rs[i],
            rr[i],
            shipped[i],
            extra.len()
        );
    }
}

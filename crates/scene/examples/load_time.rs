//! Load scenes and print the wall time of `import::load` (median of 5 runs).
//!
//! `cargo run --release -p sightline-scene --example load_time -- data/lyon1_bdtopo.geojson ...`

use sightline_scene::import::{load, ImportOptions};
use std::time::Instant;

fn main() {
    for arg in std::env::args().skip(1) {
        let mut times = Vec::new();
        let mut summary = String::new();
        let vol = |ps: &[sightline_scene::Prism]| -> f64 {
            ps.iter()
                .map(|p| p.footprint.area() * (p.top - p.base))
                .sum()
        };
        for _ in 0..5 {
            let t = Instant::now();
            match load(std::path::Path::new(&arg), &ImportOptions::default()) {
                Ok(s) => {
                    times.push(t.elapsed().as_secs_f64());
                    let inner: f64 = s.objects.iter().map(|o| vol(&o.inner)).sum();
                    let outer: f64 = s.objects.iter().map(|o| vol(&o.outer)).sum();
                    summary = format!(
                        "{} objects, {} warnings, inner/outer volume {:.3}",
                        s.len(),
                        s.warnings.len(),
                        inner / outer
                    );
                }
                Err(e) => {
                    eprintln!("error: {arg}: {e}");
                    break;
                }
            }
        }
        if times.is_empty() {
            continue;
        }
        times.sort_by(f64::total_cmp);
        println!("{arg}: {summary}, median {:.3} s", times[times.len() / 2]);
    }
}

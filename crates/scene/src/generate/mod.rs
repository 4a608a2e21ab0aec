//! Scene generators: deterministic synthetic scenes for tests and
//! benchmarks. Same seed and size → the same scene, bit for bit (same
//! [`Scene::fingerprint`](crate::Scene::fingerprint)), on any machine and thread count.
//!
//! * [`city`] — a Vienna-like old town: irregular street blocks, buildings that touch
//!   along party walls around courtyards, streets of varied width, squares, towers.
//! * [`metropolis`] — a grid city scalable to hundreds of thousands of buildings with
//!   low-rise blocks and log-normal high-rise clusters.
//! * [`forest`] — trees as meshes (trunk + many small leaf quads), the occlusion-sweep
//!   scene of the extended-projection paper (Durand et al. 2000, §7.2).
//!
//! ```
//! use sightline_scene::generate;
//! let a = generate::city(7, 40);
//! let b = generate::city(7, 40);
//! assert_eq!(a.fingerprint(), b.fingerprint());
//! ```

mod city;
mod forest;
mod metropolis;

pub use city::{city, city_with, CityParams};
pub use forest::{forest, forest_with, ForestParams};
pub use metropolis::{metropolis, metropolis_with, MetropolisParams};

/// Coordinates of generated scenes lie on a 1 mm grid and heights on a 1 cm grid: they
/// print as short decimals that every JSON/OBJ reader parses back to the same `f64`
/// (so shared vertices stay shared after a file round trip), and they are exact on
/// the 1 mm grid of [`sightline_geom::boolean`].
pub(crate) fn snap_mm(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

pub(crate) fn snap_ring(ring: Vec<sightline_geom::DVec2>) -> Vec<sightline_geom::DVec2> {
    ring.into_iter()
        .map(|p| sightline_geom::DVec2::new(snap_mm(p.x), snap_mm(p.y)))
        .collect()
}

pub(crate) fn snap_cm(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// The generators' random streams (SplitMix64, [`sightline_stats::Rng`]).
pub(crate) use sightline_stats::Rng;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_deterministic_and_uniform_enough() {
        let mut a = Rng::derive(42, 0);
        let mut b = Rng::derive(42, 0);
        for _ in 0..100 {
            assert_eq!(a.next_u64(), b.next_u64());
        }
        let mut r = Rng::derive(1, 2);
        let n = 20_000;
        let mean: f64 = (0..n).map(|_| r.f64()).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
        let m: f64 = (0..n).map(|_| r.normal()).sum::<f64>() / n as f64;
        assert!(m.abs() < 0.03, "normal mean {m}");
        assert_ne!(Rng::derive(1, 2).next_u64(), Rng::derive(1, 3).next_u64());
        assert!((0..1000).all(|_| r.below(7) < 7));
    }
}

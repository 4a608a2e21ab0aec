//! The rasterizer's benchmark workload, shared by `benches/raster.rs` and
//! `examples/raster_cpu.rs` so that both measure the same triangles.

use glam::DVec3;

/// Deterministic pseudo-random triangles of about `size` metres, 5–100 m ahead (+y).
pub fn triangles(n: usize, size: f64) -> Vec<[DVec3; 3]> {
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut r = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let y = 5.0 + 95.0 * r();
            let c = DVec3::new((r() - 0.5) * 2.0 * y, y, (r() - 0.5) * 2.0 * y);
            [0, 1, 2].map(|_| c + DVec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * size)
        })
        .collect()
}

//! The SIMD path of the masked rasterizer ([`crate::masked`]): the inner coverage of a
//! whole band of tiles — eight pixel rows — computed in lanes, one lane per row, the way
//! Masked Occlusion Culling (Hasselgren et al. 2016, §4) builds a tile's coverage mask
//! for all its rows at once; then one 8 × 32-bit mask per tile column from the rows'
//! covered pixel spans with per-lane shifts.
//!
//! Guarantee: the masks are those of the scalar path bit for bit. Each lane does the
//! scalar code's `f64` operations in the same order (chord at `j` and `j + 1` over the
//! edges, shrink by [`EPS_PX`], ceil/floor, clamp to the screen), and IEEE arithmetic
//! without fused multiply-adds is exact to the bit on every instruction set; the spans
//! are integers below 2²⁰, exact in `f32`, before they become `u32` lanes. The vector
//! code is safe (`fearless_simd`): the instruction set is detected at run time (SSE2
//! is the x86-64 baseline, AVX2 and AVX-512 when present, NEON on aarch64, a scalar
//! emulation elsewhere).

use crate::masked::{Edge, EPS_PX, TH, TILE_W};
use fearless_simd::{dispatch, f64x8, prelude::*, u32x8, Level};
use fearless_simd_macros::simd;

/// A start column past any screen (marks a row without coverage).
const NO_SPAN: f64 = (1u32 << 20) as f64;

/// The instruction set `level` stands for, for reports.
pub fn level_name(level: Level) -> &'static str {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        if level.as_avx512().is_some() {
            return "avx512";
        }
        if level.as_avx2().is_some() {
            return "avx2";
        }
        if level.as_sse4_2().is_some() {
            return "sse4.2";
        }
        if level.as_sse2().is_some() {
            return "sse2";
        }
    }
    #[cfg(target_arch = "aarch64")]
    if level.as_neon().is_some() {
        return "neon";
    }
    "fallback"
}

/// The band of tiles whose first pixel row is `ja`, rows `rows.0 ..= rows.1` of it
/// inside the polygon's range: writes `band[tx]` (all 8 rows) for every tile column
/// `tx` it returns, and only those. Same contract as the scalar `band_scalar`.
pub(crate) fn band(
    level: Level,
    edges: &[Edge],
    ja: i64,
    rows: (i64, i64),
    wf: f64,
    band: &mut [[u32; TH]],
) -> Option<(u32, u32)> {
    dispatch!(level, simd => band_lanes(simd, edges, ja, rows, wf, band))
}

#[simd]
fn band_lanes<S: Simd>(
    simd: S,
    edges: &[Edge],
    ja: i64,
    rows: (i64, i64),
    wf: f64,
    band: &mut [[u32; TH]],
) -> Option<(u32, u32)> {
    // Lane r is pixel row j = ja + r, the band [j, j + 1].
    let below = f64x8::from_fn(simd, |r| (ja + r as i64) as f64);
    let above = f64x8::from_fn(simd, |r| (ja + r as i64 + 1) as f64);
    let (mut lb, mut rb) = (f64x8::splat(simd, f64::MAX), f64x8::splat(simd, f64::MIN));
    let (mut la, mut ra) = (lb, rb);
    for &(ylo, yhi, x0, d) in edges {
        let on_b = below.simd_ge(ylo) & below.simd_le(yhi);
        let on_a = above.simd_ge(ylo) & above.simd_le(yhi);
        if yhi == ylo {
            let x1 = f64x8::splat(simd, x0 + d);
            lb = on_b.select(lb.min(x0), lb);
            rb = on_b.select(rb.max(x1), rb);
            la = on_a.select(la.min(x0), la);
            ra = on_a.select(ra.max(x1), ra);
        } else {
            // x0 + (y - ylo) * d, as the scalar chord computes it.
            let xb = (below - ylo) * d + x0;
            let xa = (above - ylo) * d + x0;
            lb = on_b.select(lb.min(xb), lb);
            rb = on_b.select(rb.max(xb), rb);
            la = on_a.select(la.min(xa), la);
            ra = on_a.select(ra.max(xa), ra);
        }
    }
    let l = lb.max(la) + EPS_PX;
    let r = rb.min(ra) - EPS_PX;
    let i0 = l.ceil().max(0.0);
    let i1 = (r.floor() - 1.0).min(wf - 1.0);
    let ok =
        below.simd_ge(rows.0 as f64) & below.simd_le(rows.1 as f64) & l.simd_le(r) & i0.simd_le(i1);
    // Covered columns [start, end) per row; empty rows get [NO_SPAN, 0).
    let start = ok.select(i0, f64x8::splat(simd, NO_SPAN));
    let end = ok.select(i1 + 1.0, f64x8::splat(simd, 0.0));
    let (start, end) = simd.split_f32x16(simd.narrow_f64x8(start, end));
    let (start, end) = (simd.cvt_u32_f32x8(start), simd.cvt_u32_f32x8(end));
    let end_max = end.reduce_max();
    if end_max == 0 {
        return None;
    }
    let (ctx_lo, ctx_hi) = ((start >> 5).reduce_min(), (end_max - 1) / TILE_W);
    let ones = u32x8::splat(simd, u32::MAX);
    let zero = u32x8::splat(simd, 0);
    let last = u32x8::splat(simd, TILE_W - 1);
    for tx in ctx_lo..=ctx_hi {
        let x0 = tx * TILE_W;
        let lo = start.max(x0);
        let hi = end.min(x0 + TILE_W);
        // Bits a ..= b of the tile, a = lo - x0, b = hi - 1 - x0 (both in 0..32 where
        // the row has pixels here; clamped into range elsewhere, then masked off).
        let a = lo.saturating_sub(x0).min(TILE_W - 1);
        let b = hi.saturating_sub(x0 + 1).min(TILE_W - 1);
        let bits = (ones >> (last - b)) & (ones << a);
        lo.simd_lt(hi)
            .select(bits, zero)
            .store_array(&mut band[tx as usize]);
    }
    Some((ctx_lo, ctx_hi))
}

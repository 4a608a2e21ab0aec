//! Delta-PVS (Durand et al. 2000, *Conservative visibility preprocessing using extended
//! projections*, §6.1): "We store the entire PVS for a single arbitrary initial cell (or
//! for a small number of seed or 'key' cells) [...] a cell simply contains the
//! difference with respect to the PVS of the neighboring cells."
//!
//! Here the choice of key cells and of each cell's reference is made to minimize the
//! stored size. Storing cell `i` whole costs `|S_i|`; storing it against neighbour `j`
//! costs `|S_i xor S_j|` (sizes of serialized roaring bitmaps). Adding a virtual root
//! whose edge to `i` costs `|S_i|`, the cheapest way to store every cell is a minimum
//! spanning tree of the neighbour graph plus the root (XOR is symmetric, so a tree can be
//! rooted anywhere): key cells are the root's children. Decoding a cell XORs the payloads
//! along its path to a key cell, so the depth is capped at [`MAX_CHAIN`] (a cell deeper
//! than that becomes a key itself) to keep a query at a few bitmap decodes.
//!
//! Everything here is a pure function of the cells and their sets (ties broken by
//! index), so the output never depends on thread scheduling.

use rayon::prelude::*;
use roaring::RoaringBitmap;
use sightline_geom::ViewCell;

/// Longest chain of payloads decoded for one cell (a key cell is a chain of 1).
pub const MAX_CHAIN: usize = sightline_runtime::wire::CHAIN_LIMIT;

/// Neighbours considered as references for each cell.
const NEIGHBOURS: usize = 8;

/// For each cell (in the order given), the position of its reference cell in the same
/// list, or `None` for a key cell. `cells[k]` and `sets[k]` describe the same cell.
pub fn choose_references(cells: &[ViewCell], sets: &[RoaringBitmap]) -> Vec<Option<usize>> {
    let n = cells.len();
    let neighbours = nearest_neighbours(cells, NEIGHBOURS);
    let neighbours = &neighbours;
    // Candidate edges (i < j) with the size of the XOR payload; a mutual pair once.
    let mut edges: Vec<(u64, usize, usize)> = neighbours
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, ns)| {
            ns.iter()
                .filter(move |&&j| j > i || !neighbours[j].contains(&i))
                .map(move |&j| {
                    let (a, b) = (i.min(j), i.max(j));
                    ((&sets[a] ^ &sets[b]).serialized_size() as u64, a, b)
                })
        })
        .collect();
    let root = n;
    edges.extend((0..n).map(|i| (sets[i].serialized_size() as u64, i, root)));
    edges.par_sort_unstable();
    edges.dedup();

    // Kruskal over the cells plus the virtual root.
    let mut uf: Vec<usize> = (0..=n).collect();
    fn find(uf: &mut [usize], mut x: usize) -> usize {
        while uf[x] != x {
            uf[x] = uf[uf[x]];
            x = uf[x];
        }
        x
    }
    let mut adjacency: Vec<Vec<usize>> = vec![Vec::new(); n + 1];
    for &(_, a, b) in &edges {
        let (ra, rb) = (find(&mut uf, a), find(&mut uf, b));
        if ra != rb {
            uf[ra.max(rb)] = ra.min(rb);
            adjacency[a].push(b);
            adjacency[b].push(a);
        }
    }
    adjacency.iter_mut().for_each(|a| a.sort_unstable());

    // Root the tree at the virtual root, breadth first; cap the depth.
    let mut reference: Vec<Option<usize>> = vec![None; n];
    let mut depth = vec![0usize; n + 1];
    let mut seen = vec![false; n + 1];
    let mut queue = std::collections::VecDeque::from([root]);
    seen[root] = true;
    while let Some(v) = queue.pop_front() {
        for &c in &adjacency[v] {
            if seen[c] {
                continue;
            }
            seen[c] = true;
            if v == root || depth[v] + 1 > MAX_CHAIN {
                depth[c] = 1;
                reference[c] = None;
            } else {
                depth[c] = depth[v] + 1;
                reference[c] = Some(v);
            }
            queue.push_back(c);
        }
    }
    reference
}

/// The `k` nearest cells of each cell by centre distance (ties by index), searched in a
/// uniform grid of centres with the median cell size as step.
fn nearest_neighbours(cells: &[ViewCell], k: usize) -> Vec<Vec<usize>> {
    let n = cells.len();
    if n < 2 {
        return vec![Vec::new(); n];
    }
    let centres: Vec<[f64; 3]> = cells.iter().map(|c| c.center().to_array()).collect();
    let mut sizes: Vec<f64> = cells
        .iter()
        .map(|c| (c.max.x - c.min.x).max(c.max.y - c.min.y))
        .collect();
    sizes.sort_by(f64::total_cmp);
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for c in &centres {
        x0 = x0.min(c[0]);
        y0 = y0.min(c[1]);
        x1 = x1.max(c[0]);
        y1 = y1.max(c[1]);
    }
    let mut step = sizes[n / 2].max((x1 - x0).max(y1 - y0) / 4096.0).max(1e-9);
    while ((x1 - x0) / step + 1.0) * ((y1 - y0) / step + 1.0) > (4 * n) as f64 {
        step *= 2.0;
    }
    let nx = ((x1 - x0) / step) as usize + 1;
    let ny = ((y1 - y0) / step) as usize + 1;
    let bucket = |c: &[f64; 3]| {
        (
            (((c[0] - x0) / step) as usize).min(nx - 1),
            (((c[1] - y0) / step) as usize).min(ny - 1),
        )
    };
    let mut buckets: Vec<Vec<usize>> = vec![Vec::new(); nx * ny];
    for (i, c) in centres.iter().enumerate() {
        let (bx, by) = bucket(c);
        buckets[by * nx + bx].push(i);
    }
    (0..n)
        .into_par_iter()
        .map(|i| {
            let (bx, by) = bucket(&centres[i]);
            let mut found: Vec<(f64, usize)> = Vec::new();
            // Grow the search ring until k candidates are found (or two rings suffice).
            let mut r = 1usize;
            loop {
                found.clear();
                for y in by.saturating_sub(r)..=(by + r).min(ny - 1) {
                    for x in bx.saturating_sub(r)..=(bx + r).min(nx - 1) {
                        for &j in &buckets[y * nx + x] {
                            if j != i {
                                let d: f64 = (0..3)
                                    .map(|a| (centres[i][a] - centres[j][a]).powi(2))
                                    .sum();
                                found.push((d, j));
                            }
                        }
                    }
                }
                if found.len() >= k || r >= 2 {
                    break;
                }
                r += 1;
            }
            found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            found.truncate(k);
            found.into_iter().map(|(_, j)| j).collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn similar_neighbours_become_deltas_and_chains_stay_short() {
        // A row of 50 cells whose sets drift slowly: one key, then deltas.
        let cells: Vec<ViewCell> = (0..50)
            .map(|i| ViewCell::from_array([i as f64, 0.0, 1.5, i as f64 + 1.0, 1.0, 2.0]).unwrap())
            .collect();
        let sets: Vec<RoaringBitmap> = (0..50u32)
            .map(|i| (i * 10..i * 10 + 2000).collect())
            .collect();
        let refs = choose_references(&cells, &sets);
        let keys = refs.iter().filter(|r| r.is_none()).count();
        assert!((1..=50 / MAX_CHAIN + 2).contains(&keys), "{keys} keys");
        for i in 0..50 {
            let mut d = 1;
            let mut c = i;
            while let Some(p) = refs[c] {
                assert!((p as i64 - c as i64).abs() <= 8, "reference is a neighbour");
                c = p;
                d += 1;
            }
            assert!(d <= MAX_CHAIN);
        }
    }

    #[test]
    fn unrelated_sets_are_keys() {
        let cells: Vec<ViewCell> = (0..4)
            .map(|i| ViewCell::from_array([i as f64, 0.0, 1.5, i as f64 + 1.0, 1.0, 2.0]).unwrap())
            .collect();
        let sets: Vec<RoaringBitmap> = (0..4u32)
            .map(|i| (i * 1000..i * 1000 + 500).collect())
            .collect();
        assert_eq!(choose_references(&cells, &sets), vec![None; 4]);
    }
}

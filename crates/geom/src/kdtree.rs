//! The hierarchical space subdivision of the occludees: a kd-tree over their boxes. Each
//! node holds the tight bounding box of the objects below it, so a child's box is
//! contained in its parent's, and a node hidden from the viewcell hides its whole
//! subtree. Used by `dual-ray` (§3 of Koltun et al. 2001) and by the occludee hierarchy
//! of `ext-proj` (its `hierarchy`, §2.4 and §6.1 of Durand et al. 2000).

use crate::Aabb3;

#[derive(Clone, Debug)]
pub enum NodeKind {
    Leaf { first: u32, len: u32 },
    Inner { left: u32, right: u32 },
}

#[derive(Clone, Debug)]
pub struct Node {
    pub bbox: Aabb3,
    pub kind: NodeKind,
}

/// A kd-tree over items `(id, box)`; `items` is permuted so that leaves own ranges.
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    pub nodes: Vec<Node>,
    pub items: Vec<(u32, Aabb3)>,
}

impl KdTree {
    /// The tree of `items`, at most `leaf_size` (≥ 1) per leaf.
    pub fn build(mut items: Vec<(u32, Aabb3)>, leaf_size: usize) -> Self {
        let mut nodes = Vec::new();
        if !items.is_empty() {
            let n = items.len();
            build_rec(&mut items, 0, n, leaf_size.max(1), &mut nodes);
        }
        KdTree { nodes, items }
    }

    pub fn leaf_items(&self, first: u32, len: u32) -> &[(u32, Aabb3)] {
        &self.items[first as usize..(first + len) as usize]
    }
}

fn build_rec(
    items: &mut [(u32, Aabb3)],
    first: usize,
    len: usize,
    leaf: usize,
    nodes: &mut Vec<Node>,
) -> u32 {
    let slice = &mut items[first..first + len];
    let bbox = slice.iter().fold(Aabb3::EMPTY, |b, (_, x)| b.union(*x));
    let id = nodes.len() as u32;
    nodes.push(Node {
        bbox,
        kind: NodeKind::Leaf {
            first: first as u32,
            len: len as u32,
        },
    });
    if len <= leaf {
        return id;
    }
    // Split at the median centre along the longer horizontal extent of the centres.
    let cb = slice
        .iter()
        .fold(Aabb3::EMPTY, |b, (_, x)| b.grow(x.center()));
    let axis = if cb.size().x >= cb.size().y { 0 } else { 1 };
    if cb.size()[axis] <= 0.0 {
        return id; // all centres coincide: keep a (large) leaf
    }
    let mid = len / 2;
    slice.select_nth_unstable_by(mid, |a, b| {
        a.1.center()[axis].total_cmp(&b.1.center()[axis])
    });
    let left = build_rec(items, first, mid, leaf, nodes);
    let right = build_rec(items, first + mid, len - mid, leaf, nodes);
    nodes[id as usize].kind = NodeKind::Inner { left, right };
    id
}

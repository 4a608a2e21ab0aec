//! The occludee hierarchy (Durand et al. 2000, §2.4: "the occludees are organized in a
//! hierarchy of axis-aligned bounding boxes"; §6.1: "the occludees are tested
//! recursively. If a node is identified as hidden or fully visible, the recursion
//! stops. By fully visible, we mean that its Projection intersects no occluder
//! Projection, in which case no child of this node can be identified as hidden").
//!
//! A node's box contains its objects' occludee boxes, so its Projection contains
//! theirs: when it is hidden, so is every object below it (the only conclusion that
//! bears on conservativeness, drawn with the same test as an object's). A fully
//! visible node only saves the tests of its objects, which go into the PVS.

use sightline_geom::Aabb3;

/// Objects per leaf at most.
pub const LEAF_OBJECTS: usize = 4;

/// What a test concludes about a node's box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Hidden,
    FullyVisible,
    Unknown,
}

/// A bounding-box hierarchy over a set of objects, built by median splits along the
/// longest axis of the boxes' centres.
pub struct Hierarchy {
    nodes: Vec<Node>,
}

struct Node {
    bounds: Aabb3,
    /// Leaf: the objects; inner: none.
    objects: Vec<u32>,
    children: Option<[usize; 2]>,
}

impl Hierarchy {
    /// The hierarchy over `ids`, each with its box `bounds(id)`.
    pub fn build(ids: &[u32], bounds: impl Fn(u32) -> Aabb3) -> Self {
        let mut items: Vec<(u32, Aabb3)> = ids.iter().map(|&i| (i, bounds(i))).collect();
        let mut h = Hierarchy { nodes: Vec::new() };
        if !items.is_empty() {
            h.split(&mut items);
        }
        h
    }

    fn split(&mut self, items: &mut [(u32, Aabb3)]) -> usize {
        let bounds = items
            .iter()
            .skip(1)
            .fold(items[0].1, |acc, (_, b)| acc.union(*b));
        let at = self.nodes.len();
        self.nodes.push(Node {
            bounds,
            objects: Vec::new(),
            children: None,
        });
        if items.len() <= LEAF_OBJECTS {
            self.nodes[at].objects = items.iter().map(|(i, _)| *i).collect();
            return at;
        }
        let s = bounds.size();
        let axis = if s.x >= s.y && s.x >= s.z {
            0
        } else if s.y >= s.z {
            1
        } else {
            2
        };
        let centre = |b: &Aabb3| b.min[axis] + b.max[axis];
        items.sort_by(|a, b| centre(&a.1).total_cmp(&centre(&b.1)).then(a.0.cmp(&b.0)));
        let (lo, hi) = items.split_at_mut(items.len() / 2);
        let l = self.split(lo);
        let r = self.split(hi);
        self.nodes[at].children = Some([l, r]);
        at
    }

    /// The objects not proven hidden: nodes are tested from the root with `test`; a
    /// hidden node drops its objects, a fully visible one keeps them all, and the
    /// objects of the leaves reached are kept when `visible(id)`. Sorted.
    pub fn visible(
        &self,
        test: impl Fn(&Aabb3) -> Verdict,
        visible: impl Fn(u32) -> bool,
    ) -> Vec<u32> {
        let mut out = Vec::new();
        let mut stack: Vec<usize> = if self.nodes.is_empty() {
            vec![]
        } else {
            vec![0]
        };
        while let Some(k) = stack.pop() {
            let node = &self.nodes[k];
            match test(&node.bounds) {
                Verdict::Hidden => {}
                Verdict::FullyVisible => self.collect(k, &mut out),
                Verdict::Unknown => match node.children {
                    Some(c) => stack.extend(c),
                    None => out.extend(node.objects.iter().copied().filter(|&i| visible(i))),
                },
            }
        }
        out.sort_unstable();
        out
    }

    fn collect(&self, k: usize, out: &mut Vec<u32>) {
        let node = &self.nodes[k];
        out.extend(&node.objects);
        if let Some(c) = node.children {
            self.collect(c[0], out);
            self.collect(c[1], out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sightline_geom::DVec3;

    fn unit(x: f64) -> Aabb3 {
        Aabb3::new(DVec3::new(x, 0.0, 0.0), DVec3::new(x + 1.0, 1.0, 1.0))
    }

    /// Twenty unit boxes along x: a test hiding every box beyond x = 10 and calling
    /// every box before x = 5 fully visible prunes whole subtrees, and the leaves in
    /// between are decided object by object.
    #[test]
    fn hidden_and_fully_visible_nodes_stop_the_recursion() {
        let ids: Vec<u32> = (0..20).collect();
        let h = Hierarchy::build(&ids, |i| unit(2.0 * i as f64));
        let tests = std::cell::Cell::new(0);
        let pvs = h.visible(
            |b| {
                tests.set(tests.get() + 1);
                if b.min.x >= 10.0 {
                    Verdict::Hidden
                } else if b.max.x <= 5.0 {
                    Verdict::FullyVisible
                } else {
                    Verdict::Unknown
                }
            },
            |i| i % 2 == 0,
        );
        // The leaf {0, 1} (x ≤ 3) is fully visible, the leaf {2, 3, 4} is decided by
        // `visible` (even ids), every node beyond x = 10 is hidden.
        assert_eq!(pvs, vec![0, 1, 2, 4]);
        assert!(tests.get() < 20, "{} node tests", tests.get());
        assert!(Hierarchy::build(&[], |i| unit(i as f64))
            .visible(|_| Verdict::Unknown, |_| true)
            .is_empty());
    }
}

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

use sightline_geom::kdtree::{KdTree, NodeKind};
use sightline_geom::Aabb3;

/// Occludees per leaf of the hierarchy.
const LEAF_SIZE: usize = 4;

/// What a test concludes about a node's box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Verdict {
    Hidden,
    FullyVisible,
    Unknown,
}

/// A bounding-box hierarchy over a set of objects (the kd-tree of `dual-ray`, one box
/// per object).
pub(crate) struct Hierarchy {
    tree: KdTree,
}

impl Hierarchy {
    /// The hierarchy over `ids`, each with its box `bounds(id)`.
    pub(crate) fn build(ids: &[u32], bounds: impl Fn(u32) -> Aabb3) -> Self {
        Hierarchy {
            tree: KdTree::build(ids.iter().map(|&i| (i, bounds(i))).collect(), LEAF_SIZE),
        }
    }

    /// The objects not proven hidden: nodes are tested from the root with `test`; a
    /// hidden node drops its objects, a fully visible one keeps them all, and the
    /// objects of the leaves reached are kept when `visible(id)`. Sorted.
    pub(crate) fn visible(
        &self,
        test: impl Fn(&Aabb3) -> Verdict,
        visible: impl Fn(u32) -> bool,
    ) -> Vec<u32> {
        let mut out = Vec::new();
        let mut stack: Vec<u32> = if self.tree.nodes.is_empty() {
            vec![]
        } else {
            vec![0]
        };
        while let Some(k) = stack.pop() {
            let node = &self.tree.nodes[k as usize];
            match test(&node.bbox) {
                Verdict::Hidden => {}
                Verdict::FullyVisible => self.collect(k, &mut out),
                Verdict::Unknown => match node.kind {
                    NodeKind::Inner { left, right } => stack.extend([left, right]),
                    NodeKind::Leaf { first, len } => out.extend(
                        self.tree
                            .leaf_items(first, len)
                            .iter()
                            .map(|(i, _)| *i)
                            .filter(|&i| visible(i)),
                    ),
                },
            }
        }
        out.sort_unstable();
        out
    }

    fn collect(&self, k: u32, out: &mut Vec<u32>) {
        match self.tree.nodes[k as usize].kind {
            NodeKind::Inner { left, right } => {
                self.collect(left, out);
                self.collect(right, out);
            }
            NodeKind::Leaf { first, len } => {
                out.extend(self.tree.leaf_items(first, len).iter().map(|(i, _)| *i))
            }
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

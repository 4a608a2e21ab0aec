//! Small hand-built levels for tests and examples: two rooms behind a thin wall with a
//! square hole in it, and two rooms that meet only along an edge.

use sightline_scene::import::bsp::{
    BspFace, BspLeaf, BspLevel, BspNode, BspPlane, Child, CONTENTS_EMPTY, CONTENTS_SOLID,
};

/// Two rooms `x ∈ [-100, -1]` and `x ∈ [1, 100]` (`y, z ∈ [-50, 50]`) separated by a
/// wall 2 units thick, with a square hole of side `hole` centred on the x axis
/// (no hole when `hole <= 0`). Leaves: 0 solid, 1 the west room, 2 the east room, 3 the
/// hole. Faces: 0 the west room's far wall (x = -100, facing east), 1 the east room's
/// far wall (x = 100, facing west), 2 the east face of the wall, facing east.
pub fn two_rooms(hole: f64) -> BspLevel {
    let h = hole.max(0.0) / 2.0;
    let plane = |n: [f64; 3], d: f64| BspPlane { normal: n, dist: d };
    let planes = vec![
        plane([1.0, 0.0, 0.0], -100.0),  // 0: x > -100
        plane([-1.0, 0.0, 0.0], -100.0), // 1: x < 100
        plane([0.0, 1.0, 0.0], -50.0),   // 2: y > -50
        plane([0.0, -1.0, 0.0], -50.0),  // 3: y < 50
        plane([0.0, 0.0, 1.0], -50.0),   // 4: z > -50
        plane([0.0, 0.0, -1.0], -50.0),  // 5: z < 50
        plane([-1.0, 0.0, 0.0], 1.0),    // 6: x < -1
        plane([1.0, 0.0, 0.0], 1.0),     // 7: x > 1
        plane([0.0, 1.0, 0.0], -h),      // 8: y > -h
        plane([0.0, -1.0, 0.0], -h),     // 9: y < h
        plane([0.0, 0.0, 1.0], -h),      // 10: z > -h
        plane([0.0, 0.0, -1.0], -h),     // 11: z < h
    ];
    let solid = Child::Leaf(0);
    let node = |plane: u32, front: Child, back: Child| BspNode {
        plane,
        children: [front, back],
    };
    let wall = if hole > 0.0 { Child::Node(8) } else { solid };
    let nodes = vec![
        node(0, Child::Node(1), solid),
        node(1, Child::Node(2), solid),
        node(2, Child::Node(3), solid),
        node(3, Child::Node(4), solid),
        node(4, Child::Node(5), solid),
        node(5, Child::Node(6), solid),
        node(6, Child::Leaf(1), Child::Node(7)),
        node(7, Child::Leaf(2), wall),
        node(8, Child::Node(9), solid),
        node(9, Child::Node(10), solid),
        node(10, Child::Node(11), solid),
        node(11, Child::Leaf(3), solid),
    ];
    let leaf = |contents: i32, mins: [f64; 3], maxs: [f64; 3], faces: Vec<u32>| BspLeaf {
        contents,
        visofs: -1,
        mins,
        maxs,
        faces,
    };
    let leaves = vec![
        leaf(CONTENTS_SOLID, [0.0; 3], [0.0; 3], vec![]),
        leaf(
            CONTENTS_EMPTY,
            [-100.0, -50.0, -50.0],
            [-1.0, 50.0, 50.0],
            vec![0],
        ),
        leaf(
            CONTENTS_EMPTY,
            [1.0, -50.0, -50.0],
            [100.0, 50.0, 50.0],
            vec![1, 2],
        ),
        leaf(CONTENTS_EMPTY, [-1.0, -h, -h], [1.0, h, h], vec![]),
    ];
    let square = |x: f64| {
        vec![
            [x, -50.0, -50.0],
            [x, 50.0, -50.0],
            [x, 50.0, 50.0],
            [x, -50.0, 50.0],
        ]
    };
    let face = |polygon: Vec<[f64; 3]>, plane: u32, back: bool| BspFace {
        polygon,
        plane,
        back,
        texture: "wall".into(),
        leaves: vec![],
    };
    let faces = vec![
        face(square(-100.0), 0, false),
        face(square(100.0), 1, false),
        face(square(1.0), 7, false),
    ];
    BspLevel::from_parts(planes, nodes, leaves, faces, Child::Node(0), 3, Vec::new())
        .expect("a valid hand-built level")
}

/// Two rooms that meet only along an edge: the box `x ∈ [-100, 100]`,
/// `y ∈ [-50, 50]`, `z ∈ [-50, 50]` cut into quarters by `x = 0` and `y = 0`, the
/// quarters `x, y > 0` (leaf 1) and `x, y < 0` (leaf 2) open, the other two solid. The
/// rooms share the segment `x = y = 0`, through which lines only graze: they must not
/// see each other.
pub fn corner_rooms() -> BspLevel {
    let plane = |n: [f64; 3], d: f64| BspPlane { normal: n, dist: d };
    let planes = vec![
        plane([1.0, 0.0, 0.0], -100.0),  // 0: x > -100
        plane([-1.0, 0.0, 0.0], -100.0), // 1: x < 100
        plane([0.0, 1.0, 0.0], -50.0),   // 2: y > -50
        plane([0.0, -1.0, 0.0], -50.0),  // 3: y < 50
        plane([0.0, 0.0, 1.0], -50.0),   // 4: z > -50
        plane([0.0, 0.0, -1.0], -50.0),  // 5: z < 50
        plane([1.0, 0.0, 0.0], 0.0),     // 6: x > 0
        plane([0.0, 1.0, 0.0], 0.0),     // 7: y > 0
    ];
    let solid = Child::Leaf(0);
    let node = |plane: u32, front: Child, back: Child| BspNode {
        plane,
        children: [front, back],
    };
    let nodes = vec![
        node(0, Child::Node(1), solid),
        node(1, Child::Node(2), solid),
        node(2, Child::Node(3), solid),
        node(3, Child::Node(4), solid),
        node(4, Child::Node(5), solid),
        node(5, Child::Node(6), solid),
        node(6, Child::Node(7), Child::Node(8)),
        node(7, Child::Leaf(1), solid),
        node(7, solid, Child::Leaf(2)),
    ];
    let leaf = |contents: i32, mins: [f64; 3], maxs: [f64; 3]| BspLeaf {
        contents,
        visofs: -1,
        mins,
        maxs,
        faces: vec![],
    };
    let leaves = vec![
        leaf(CONTENTS_SOLID, [0.0; 3], [0.0; 3]),
        leaf(CONTENTS_EMPTY, [0.0, 0.0, -50.0], [100.0, 50.0, 50.0]),
        leaf(CONTENTS_EMPTY, [-100.0, -50.0, -50.0], [0.0, 0.0, 50.0]),
    ];
    BspLevel::from_parts(
        planes,
        nodes,
        leaves,
        Vec::new(),
        Child::Node(0),
        2,
        Vec::new(),
    )
    .expect("a valid hand-built level")
}

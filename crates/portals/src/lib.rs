//! Cells and portals for BSP levels: the leaves of a compiled Quake tree are the cells,
//! the openings between open leaves the portals, and a leaf sees another only through
//! a sequence of portals that a line can stab — Teller & Séquin, "Visibility
//! preprocessing for interactive walkthroughs" (SIGGRAPH 1991), in the form of the
//! visibility course's `Find_Visible_Cells(cell, portal sequence, visible set)`, with
//! stabbing tested by separating planes as Quake's `vis` does (see [`flow`]).
//!
//! Guarantee: a leaf or face is reported hidden from a leaf only if no line from a
//! point of the leaf reaches it through open space (solid and sky block, liquids do
//! not); ties, grazing lines and slivers thinner than `ON_EPSILON` count as visible.
//!
//! * [`winding`] — convex polygons clipped by planes, erring towards keeping;
//! * [`portalize`] — portals from the tree, as qbsp builds them;
//! * [`flow`] — the base flood (`portals-fast`) and the flow through portal sequences
//!   with separating planes (`portals`), and the face test;
//! * [`oracle`] — rays through the tree, independent of the above, for the tests;
//! * [`prt`] — qbsp's portal files (`PRT1`), an alternative to [`portalize`];
//! * [`vislump`] — the level's visibility lump written as Quake engines read it.
//!
//! ```
//! use sightline_portals::{Mode, Portals};
//! use sightline_portals::testlevel::two_rooms;
//! let level = two_rooms(2.0);
//! let portals = Portals::build(&level).unwrap();
//! let room = level.point_leaf([-50.0, 0.0, 0.0]);
//! let pvs = portals.solve(room, Mode::Full);
//! assert!(pvs.leaves.contains(&level.point_leaf([50.0, 0.0, 0.0])));
//! ```

pub mod bits;
pub mod cells;
pub mod flow;
pub mod method;
pub mod oracle;
pub mod portalize;
pub mod prt;
pub mod reference;
pub mod testlevel;
pub mod vislump;
pub mod winding;

pub use cells::leaf_cells;
pub use method::PortalMethod;

use bits::Bits;
use flow::{DirPortal, Graph, Seen};
use portalize::Portal;
use rayon::prelude::*;
use sightline_geom::DVec3;
use sightline_scene::import::bsp::BspLevel;
use winding::{Plane, Winding, ON_EPSILON};

/// Which bound to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Flow through portal sequences with separating planes (`portals`).
    Full,
    /// The base flood only (`portals-fast`): cheaper, always contains `Full`.
    Fast,
}

/// The PVS of one leaf: leaves and world faces, each sorted ascending.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LeafPvs {
    pub leaf: u32,
    pub leaves: Vec<u32>,
    pub faces: Vec<u32>,
}

/// Why a level could not be prepared.
#[derive(Debug, thiserror::Error)]
pub enum PortalError {
    #[error("the level has no open leaves")]
    Empty,
    #[error(transparent)]
    Prt(#[from] prt::PrtError),
}

/// The portals of a level, ready to answer leaf PVS queries.
pub struct Portals {
    level: BspLevel,
    portals: Vec<Portal>,
    graph: Graph,
    /// Base flood of each directed portal.
    mightsee: Vec<Seen>,
    /// Each face's polygon and front plane; two-sided liquid surfaces flagged.
    faces: Vec<(Winding, Plane, bool)>,
    /// Flow result of every directed portal, computed on first use.
    flows: std::sync::OnceLock<Vec<Seen>>,
}

impl Portals {
    /// Portalize `level` and flood every portal.
    pub fn build(level: &BspLevel) -> Result<Portals, PortalError> {
        if !(1..=level.visleafs).any(|l| level.is_view_leaf(l)) {
            return Err(PortalError::Empty);
        }
        Self::with_portals(level, portalize::portalize(level))
    }

    /// The portals of qbsp's portal file instead of the tree's: checked against the
    /// level (see [`prt::portals_for_level`]), then flooded.
    pub fn from_prt(level: &BspLevel, file: &prt::Prt) -> Result<Portals, PortalError> {
        if !(1..=level.visleafs).any(|l| level.is_view_leaf(l)) {
            return Err(PortalError::Empty);
        }
        let portals = prt::portals_for_level(file, level)?;
        Self::with_portals(level, portals)
    }

    fn with_portals(level: &BspLevel, portals: Vec<Portal>) -> Result<Portals, PortalError> {
        let graph = Graph::from_portals(
            level.leaves.len(),
            portals.iter().map(|p| (&p.winding, p.plane, p.leaves)),
        );
        let mightsee = flow::might_see_all(&graph);
        let faces = level
            .faces
            .iter()
            .map(|f| {
                let bp = level.planes[f.plane as usize];
                let mut plane = Plane::new(DVec3::from(bp.normal), bp.dist);
                if f.back {
                    plane = plane.flipped();
                }
                let w = Winding::new(f.polygon.iter().map(|p| DVec3::from(*p)).collect());
                (
                    w,
                    plane,
                    sightline_scene::import::bsp::is_liquid(&f.texture),
                )
            })
            .collect();
        Ok(Portals {
            level: level.clone(),
            portals,
            graph,
            mightsee,
            faces,
            flows: std::sync::OnceLock::new(),
        })
    }

    pub fn level(&self) -> &BspLevel {
        &self.level
    }

    /// The undirected portals between open leaves.
    pub fn portals(&self) -> &[Portal] {
        &self.portals
    }

    /// The portal graph (each portal in both directions).
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// The PVS of one leaf. `Mode::Full` runs the flow of every portal of the level
    /// on first use (each portal's flow bounds the flows that pass through it, as in
    /// vis), then answers from it.
    pub fn solve(&self, leaf: u32, mode: Mode) -> LeafPvs {
        let vis = self.portal_sets(mode);
        self.leaf_pvs(leaf, vis, mode)
    }

    /// The PVS of one leaf from the flows of its own portals alone, each bounded only
    /// by the base floods: no level-wide precomputation, looser than [`Portals::solve`]
    /// and still conservative.
    pub fn solve_local(&self, leaf: u32) -> LeafPvs {
        let none = vec![None; self.graph.portals.len()];
        let own: Vec<(u32, Seen)> = self
            .graph
            .leaf_portals
            .get(leaf as usize)
            .map(|out| {
                out.iter()
                    .map(|&p| {
                        let f = flow::flow(&self.graph, p as usize, &self.mightsee, &none);
                        (p, f)
                    })
                    .collect()
            })
            .unwrap_or_default();
        let v: Vec<(u32, &Seen)> = own.iter().map(|(p, f)| (*p, f)).collect();
        self.assemble(leaf, &v, Mode::Full)
    }

    /// The PVS of every leaf `0 ..= visleafs`, in leaf order (leaf 0 and other
    /// closed leaves see only themselves).
    pub fn solve_all(&self, mode: Mode) -> Vec<LeafPvs> {
        let vis = self.portal_sets(mode);
        (0..=self.level.visleafs)
            .into_par_iter()
            .map(|leaf| self.leaf_pvs(leaf, vis, mode))
            .collect()
    }

    /// What each directed portal sees: its base flood (`Fast`) or its flow (`Full`).
    pub fn portal_sets(&self, mode: Mode) -> &[Seen] {
        match mode {
            Mode::Fast => &self.mightsee,
            Mode::Full => self
                .flows
                .get_or_init(|| flow::flow_all(&self.graph, &self.mightsee)),
        }
    }

    /// The leaves each leaf `1 ..= visleafs` sees (itself included), from what each
    /// directed portal sees (`portal_sets`, or a flow computed with
    /// [`flow::flow_all_resumable`]): `out[l - 1]` for leaf `l`. These are exactly the
    /// `leaves` of [`Portals::solve_all`], without the face test.
    pub fn visleaf_sets(&self, seen: &[Seen]) -> Vec<Bits> {
        (1..=self.level.visleafs)
            .into_par_iter()
            .map(|l| flow::cell_pvs(&self.graph, seen, l))
            .collect()
    }

    fn leaf_pvs(&self, leaf: u32, vis: &[Seen], mode: Mode) -> LeafPvs {
        let v: Vec<(u32, &Seen)> = self
            .graph
            .leaf_portals
            .get(leaf as usize)
            .map(|out| out.iter().map(|&p| (p, &vis[p as usize])).collect())
            .unwrap_or_default();
        self.assemble(leaf, &v, mode)
    }

    /// Leaves and faces of `leaf` from what its outgoing portals see. A face of a leaf
    /// entered by portal `q` (beyond the source portal `p`'s own leaf) is kept when a
    /// line through `p` and then `q` can reach it; every line through `p` into that
    /// leaf enters by a portal of `p`'s portal set.
    fn assemble(&self, leaf: u32, vis: &[(u32, &Seen)], mode: Mode) -> LeafPvs {
        let level = &self.level;
        let g = &self.graph;
        let mut leaves = Bits::new(level.leaves.len());
        let mut faces = Bits::new(level.faces.len());
        let mark_all = |faces: &mut Bits, l: usize| {
            for &f in &level.leaves[l].faces {
                faces.set(f as usize);
            }
        };
        leaves.set(leaf as usize);
        mark_all(&mut faces, leaf as usize);
        for (p, v) in vis {
            let pp = &g.portals[*p as usize];
            leaves.or(&v.cells);
            mark_all(&mut faces, pp.to as usize);
            for q in v.portals.ones() {
                let qp = &g.portals[q];
                let l = qp.to as usize;
                let lf = &level.leaves[l].faces;
                if lf.iter().all(|&f| faces.get(f as usize)) {
                    continue;
                }
                if mode == Mode::Fast {
                    mark_all(&mut faces, l);
                    continue;
                }
                // Lines through p then q: p's part behind q, separating planes of both.
                let Some(source) = pp.winding.clip(&qp.plane.flipped(), ON_EPSILON) else {
                    continue;
                };
                let mut seps = flow::separators(&source, &qp.winding, false);
                seps.extend(flow::separators(&qp.winding, &source, true));
                for &f in lf {
                    if faces.get(f as usize) {
                        continue;
                    }
                    if self.face_reachable(&source, pp, qp, &seps, f as usize) {
                        faces.set(f as usize);
                    }
                }
            }
        }
        LeafPvs {
            leaf,
            leaves: leaves.ones().map(|l| l as u32).collect(),
            faces: faces.ones().map(|f| f as u32).collect(),
        }
    }

    fn face_reachable(
        &self,
        source: &Winding,
        p: &DirPortal,
        q: &DirPortal,
        seps: &[Plane],
        f: usize,
    ) -> bool {
        let (w, plane, two_sided) = &self.faces[f];
        if w.len() < 3 {
            return false;
        }
        // A line reaching the face's front crosses its plane once, at the face: both
        // portals, which it passes before, lie in front of the face.
        let faces_viewer =
            source.any_front(plane, -ON_EPSILON) && q.winding.any_front(plane, -ON_EPSILON);
        if !(*two_sided || faces_viewer) {
            return false;
        }
        let Some(mut w) = w
            .clip(&p.plane, ON_EPSILON)
            .and_then(|w| w.clip(&q.plane, ON_EPSILON))
        else {
            return false;
        };
        for s in seps {
            match w.clip(s, ON_EPSILON) {
                Some(c) => w = c,
                None => return false,
            }
        }
        true
    }
}

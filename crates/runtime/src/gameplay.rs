//! Gameplay queries derived from the stored rows: can cell `a` see cell `b`, which cells
//! can see a point, and the secondary PVS (what the cells a cell can see can see).
//!
//! **Guarantee.** `can_see(a, b)` never answers `false` for a pair of cells between
//! which the rows it derives from admit a line of sight; how far that reaches depends on
//! what the file stores ([`CellRelation`]):
//!
//! * [`CellRelation::Leaves`] (a LEAF section: a BSP level's build). The rows list
//!   *cells*: `a` sees `b` when `b ∈ L(a)` **and** `a ∈ L(b)`. Each leaf PVS is
//!   conservative and visibility is symmetric, so a sight line between `a` and `b` puts
//!   `b` in `L(a)` and `a` in `L(b)`: the intersection is still conservative, and
//!   tighter than either side. Fully conservative.
//! * [`CellRelation::SharedObjects`] (city and mesh files: the rows list *objects*, and
//!   the file has no geometry to place an object in a cell). `a` sees `b` when their
//!   rows share an object. A sight line from `p ∈ a` to `q ∈ b`, extended past `q`,
//!   ends on a surface `S`; `S` is seen from `q` and, through `q`, from `p`, so `S`'s
//!   object is in both rows. This is conservative whenever every sight line through
//!   the cells' free space, extended either way, ends on an object: closed levels
//!   (indoor meshes, walled arenas). Under an open sky a line that escapes to the sky
//!   or to bare ground at both ends is not covered, so there the relation is
//!   "the two cells see a common object", a heuristic, not a proof of invisibility.
//!
//! A cell always sees itself. Both relations are symmetric, so the cells that can see
//! cell `b` are the cells `b` can see, and the secondary PVS of `a` is the union of the
//! rows of the cells that see `a`. A shard file answers about its stored cells only.

use crate::error::{corrupt, RuntimeError};
use crate::file::Pvs;
use crate::query::Query;

/// How [`Pvs::can_see`] relates two cells (module documentation: the guarantee).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellRelation {
    /// Through the visible leaves of the LEAF section: conservative.
    Leaves,
    /// Through the objects two cells' rows share: conservative in closed scenes.
    SharedObjects,
}

/// Every stored row, forward (cell → objects) and inverse (object → cells), built on
/// the first gameplay query that needs it (or by [`Pvs::prepare_gameplay`]).
pub(crate) struct Index {
    row_offsets: Vec<usize>,
    rows: Vec<u32>,
    inv_offsets: Vec<usize>,
    inv: Vec<u32>,
    /// One more than the largest id in any row.
    objects: usize,
}

impl Index {
    fn build(pvs: &Pvs) -> Result<Index, RuntimeError> {
        let n = pvs.cell_count() as usize;
        let mut q = Query::new();
        let mut row = Vec::new();
        let mut row_offsets = Vec::with_capacity(n + 1);
        let mut rows = Vec::new();
        row_offsets.push(0);
        for c in 0..n as u32 {
            if pvs.is_stored(c) {
                pvs.visible_into(&mut q, c, &mut row)?;
                rows.extend_from_slice(&row);
            }
            row_offsets.push(rows.len());
        }
        // Sized by the largest id present, not the header's object count (a hostile
        // header may claim billions of objects).
        let objects = rows.iter().max().map_or(0, |&m| m as usize + 1);
        let mut counts = vec![0usize; objects + 1];
        for &o in &rows {
            counts[o as usize + 1] += 1;
        }
        for k in 0..objects {
            counts[k + 1] += counts[k];
        }
        let inv_offsets = counts.clone();
        let mut fill = counts;
        let mut inv = vec![0u32; rows.len()];
        for c in 0..n {
            for &o in &rows[row_offsets[c]..row_offsets[c + 1]] {
                inv[fill[o as usize]] = c as u32;
                fill[o as usize] += 1;
            }
        }
        Ok(Index {
            row_offsets,
            rows,
            inv_offsets,
            inv,
            objects,
        })
    }

    fn row(&self, c: u32) -> &[u32] {
        &self.rows[self.row_offsets[c as usize]..self.row_offsets[c as usize + 1]]
    }

    fn cells_of(&self, object: u32) -> &[u32] {
        &self.inv[self.inv_offsets[object as usize]..self.inv_offsets[object as usize + 1]]
    }
}

fn intersects(a: &[u32], b: &[u32]) -> bool {
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => return true,
        }
    }
    false
}

/// Clear `marks` to `bits` zero bits, allocation-free once grown.
fn reset(marks: &mut Vec<u64>, bits: usize) {
    marks.clear();
    marks.resize(bits.div_ceil(64), 0);
}

fn mark(marks: &mut [u64], i: u32) {
    marks[i as usize / 64] |= 1 << (i % 64);
}

fn collect(marks: &[u64], out: &mut Vec<u32>) {
    out.clear();
    for (w, &bits) in marks.iter().enumerate() {
        let mut bits = bits;
        while bits != 0 {
            out.push(w as u32 * 64 + bits.trailing_zeros());
            bits &= bits - 1;
        }
    }
}

impl Pvs {
    /// How [`Pvs::can_see`] relates cells in this file.
    pub fn cell_relation(&self) -> CellRelation {
        if self.has_visible_leaves() {
            CellRelation::Leaves
        } else {
            CellRelation::SharedObjects
        }
    }

    /// The number a LEAF set uses for cell `c`: its SHAP id, or its index without SHAP.
    fn leaf_number(&self, c: u32) -> u32 {
        self.source_number(c)
    }

    fn check_stored(&self, c: u32) -> Result<(), RuntimeError> {
        if self.is_stored(c) {
            Ok(())
        } else {
            Err(RuntimeError::Invalid(format!(
                "cell {c} is not stored in this file"
            )))
        }
    }

    fn index(&self) -> Result<&Index, RuntimeError> {
        match self
            .gameplay
            .get_or_init(|| Index::build(self).map_err(|e| e.to_string()))
        {
            Ok(i) => Ok(i),
            Err(e) => corrupt(e.clone()),
        }
    }

    /// Decode every row once and build the inverse index the gameplay queries use (they
    /// build it on first use otherwise): memory of the order of the sum of all rows.
    pub fn prepare_gameplay(&self) -> Result<(), RuntimeError> {
        self.index().map(|_| ())
    }

    /// Whether cell `a` may see cell `b` (conservative as the module documentation
    /// states; `true` for `a == b`). An error for a cell the file does not store.
    pub fn can_see(&self, q: &mut Query, a: u32, b: u32) -> Result<bool, RuntimeError> {
        self.check_stored(a)?;
        self.check_stored(b)?;
        if a == b {
            return Ok(true);
        }
        match self.cell_relation() {
            CellRelation::Leaves => {
                let (la, lb) = (self.visible_leaves(a), self.visible_leaves(b));
                let (la, lb) = (la.unwrap_or(&[]), lb.unwrap_or(&[]));
                Ok(la.binary_search(&self.leaf_number(b)).is_ok()
                    && lb.binary_search(&self.leaf_number(a)).is_ok())
            }
            CellRelation::SharedObjects => {
                let (mut ra, mut rb) = (std::mem::take(&mut q.other), std::mem::take(&mut q.row));
                let r = self
                    .visible_into(q, a, &mut ra)
                    .and_then(|_| self.visible_into(q, b, &mut rb))
                    .map(|_| intersects(&ra, &rb));
                (q.other, q.row) = (ra, rb);
                r
            }
        }
    }

    /// The cells that may see cell `b` (those `b` may see: the relation is symmetric),
    /// ascending, `b` included, into `out`.
    pub fn cells_seeing_into(
        &self,
        q: &mut Query,
        b: u32,
        out: &mut Vec<u32>,
    ) -> Result<(), RuntimeError> {
        out.clear();
        self.check_stored(b)?;
        match self.cell_relation() {
            CellRelation::Leaves => {
                let nb = self.leaf_number(b);
                for &l in self.visible_leaves(b).unwrap_or(&[]) {
                    let from = self.by_source_id.partition_point(|&(s, _)| s < l);
                    for &(s, a) in &self.by_source_id[from..] {
                        if s != l {
                            break;
                        }
                        if self
                            .visible_leaves(a)
                            .is_some_and(|la| la.binary_search(&nb).is_ok())
                        {
                            out.push(a);
                        }
                    }
                }
                out.push(b);
                out.sort_unstable();
                out.dedup();
            }
            CellRelation::SharedObjects => {
                let index = self.index()?;
                reset(&mut q.marks, self.cell_count() as usize);
                mark(&mut q.marks, b);
                for &o in index.row(b) {
                    for &a in index.cells_of(o) {
                        mark(&mut q.marks, a);
                    }
                }
                collect(&q.marks, out);
            }
        }
        Ok(())
    }

    /// The cells that may see the point `p` (module documentation), ascending, into
    /// `out`; returns the cell holding `p`, `None` (and `out` empty) outside every cell.
    pub fn cells_seeing_point_into(
        &self,
        q: &mut Query,
        p: [f64; 3],
        out: &mut Vec<u32>,
    ) -> Result<Option<u32>, RuntimeError> {
        out.clear();
        match self.locate(p) {
            None => Ok(None),
            Some(b) => self.cells_seeing_into(q, b, out).map(|_| Some(b)),
        }
    }

    /// The secondary PVS of cell `a`: the union of the rows of the cells that may see
    /// `a` (its own row included), ascending, into `out`. What an AI or a network
    /// update may need to consider when something in `a` can affect what is seen.
    pub fn secondary_into(
        &self,
        q: &mut Query,
        a: u32,
        out: &mut Vec<u32>,
    ) -> Result<(), RuntimeError> {
        out.clear();
        let mut cells = std::mem::take(&mut q.other);
        let r = self.cells_seeing_into(q, a, &mut cells);
        if let Err(e) = r {
            q.other = cells;
            return Err(e);
        }
        let index = match self.index() {
            Ok(i) => i,
            Err(e) => {
                q.other = cells;
                return Err(e);
            }
        };
        reset(&mut q.marks, index.objects);
        for &c in &cells {
            for &o in index.row(c) {
                mark(&mut q.marks, o);
            }
        }
        collect(&q.marks, out);
        q.other = cells;
        Ok(())
    }
}

//! Where PVS answers come from: a `.pvs` file built beforehand, or a visibility method
//! run on-line (dual ray space paper, §1: "computing from-region visibility on-line,
//! thus eliminating the need for visibility preprocessing").
//!
//! Both sit behind [`PvsSource`]; the server puts a cache and a worker pool in front
//! ([`crate::cache`]) and never asks a source about anything but cells it located itself.

use crate::grid::{CellGrid, CellId, PointError, MAX_CELLS};
use crate::layout::{CellSet, CellSetError, Layout};
use serde::Serialize;
use sightline_geom::{DVec2, DVec3, ViewCell};
use sightline_methods::VisibilityMethod;
use sightline_pvs::PvsFile;
use sightline_scene::Scene;
use std::sync::Arc;

/// What a source says about itself (shown in `/api/scene`).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SourceInfo {
    /// `"online"`, `"file"`, or `"memory"` (a `.pvs` built at start-up and held in
    /// memory, see [`FileSource::in_memory`]).
    pub kind: &'static str,
    /// The name of the method that produced / produces the sets.
    pub method: String,
    /// Whether every set contains every visible object.
    pub conservative: bool,
    /// The method's parameters, `key=value`.
    pub params: Vec<String>,
}

/// Why a source could not give a cell's PVS.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum SourceError {
    #[error("no such cell {0}")]
    NoCell(CellId),
    #[error("{0}")]
    Method(String),
}

/// A provider of per-cell PVS, blocking (call it from a worker thread).
pub trait PvsSource: Send + Sync + 'static {
    fn info(&self) -> SourceInfo;
    /// The cell layout: sessions prefetch along it.
    fn layout(&self) -> Layout<'_>;
    /// The cell containing a point.
    fn locate(&self, p: DVec3) -> Result<CellId, PointError> {
        match self.layout() {
            Layout::Grid(g) => g.locate(p),
            Layout::Cells(c) => c.locate_box(p),
        }
    }
    /// The box of a cell (a shaped cell's bounding box).
    fn cell(&self, id: CellId) -> Option<ViewCell> {
        self.layout().cell(id)
    }
    /// The cells adjacent to `id`, those ahead along `heading` first.
    fn neighbours(&self, id: CellId, heading: DVec2) -> Vec<CellId> {
        self.layout().neighbours(id, heading)
    }
    /// The cell a client at `p` moving along `heading` enters next, if known: on a grid
    /// the neighbour across the side the motion leaves through
    /// ([`CellGrid::next_cell`]); on a cell set the cell holding the point just beyond
    /// the current cell's box along the motion ([`CellSet::exit_point`]).
    fn next_cell(&self, p: DVec3, heading: DVec2) -> Option<CellId> {
        match self.layout() {
            Layout::Grid(g) => g.next_cell(p.truncate(), heading),
            Layout::Cells(c) => {
                let here = self.locate(p).ok()?;
                let beyond = c.exit_point(here, p, heading)?;
                self.locate(beyond).ok().filter(|&n| n != here)
            }
        }
    }
    /// The cell `steps` cells ahead of `id` along `heading` (grids only: a cell set has
    /// no rows to count along).
    fn ahead(&self, id: CellId, heading: DVec2, steps: u32) -> Option<CellId> {
        self.layout().grid()?.ahead(id, heading, steps)
    }
    /// The PVS of a cell: sorted ascending object ids. May take long (on-line methods).
    fn pvs(&self, id: CellId) -> Result<Vec<u32>, SourceError>;
}

/// On-line source: a prepared [`VisibilityMethod`] evaluated per grid cell.
pub struct OnlineSource {
    method: Box<dyn VisibilityMethod>,
    grid: CellGrid,
}

impl OnlineSource {
    pub fn new(method: Box<dyn VisibilityMethod>, grid: CellGrid) -> Self {
        OnlineSource { method, grid }
    }
}

impl PvsSource for OnlineSource {
    fn info(&self) -> SourceInfo {
        SourceInfo {
            kind: "online",
            method: self.method.name().to_string(),
            conservative: self.method.is_conservative(),
            params: self
                .method
                .params()
                .into_iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect(),
        }
    }

    fn layout(&self) -> Layout<'_> {
        Layout::Grid(&self.grid)
    }

    fn pvs(&self, id: CellId) -> Result<Vec<u32>, SourceError> {
        let cell = self.grid.cell(id).ok_or(SourceError::NoCell(id))?;
        let mut v = self
            .method
            .pvs(&cell)
            .map_err(|e| SourceError::Method(e.to_string()))?;
        // The trait promises sorted, unique ids; the deltas rely on it, so make sure.
        if !v.windows(2).all(|w| w[0] < w[1]) {
            v.sort_unstable();
            v.dedup();
        }
        Ok(v)
    }
}

/// File source: the sets of a `.pvs` built beforehand (`sightline build`), served on
/// one of two layouts:
///
/// * [`FileSource::new`]: a regular grid of square cells — what `sightline cells` writes
///   for a city. Grid cells the file lacks (the grid's cells inside buildings, which
///   `cells` drops) answer [`SourceError::NoCell`];
/// * [`FileSource::cells`]: the file's own cells, whatever their shapes — a BSP level's
///   leaves (convex cells), a mesh level's automatic cells. Cell `i` is the file's cell
///   `i`; a point is located as `query --at` locates it ([`PvsFile::locate`]: the
///   spatial index over the cells' boxes, then the cell's shape), so the cell served is
///   the one whose PVS `query` answers.
pub struct FileSource {
    file: PvsFile,
    layout: FileLayout,
    kind: &'static str,
}

enum FileLayout {
    Grid {
        grid: CellGrid,
        /// Grid cell id → index of the file's cell.
        index: Vec<Option<u32>>,
    },
    Cells(CellSet),
}

/// Why a `.pvs` file cannot be served.
#[derive(Debug, thiserror::Error)]
pub enum FileSourceError {
    #[error(transparent)]
    Pvs(#[from] sightline_pvs::PvsError),
    #[error("the file is shard {0}/{1}: merge the shards first (`sightline merge`)")]
    Shard(u32, u32),
    #[error("the file has no cells")]
    Empty,
    #[error("cell {0} ({1}) is not a square of the grid of cell 0 ({2}): serving needs the regular grid of `sightline cells`")]
    NotAGrid(usize, ViewCell, ViewCell),
    #[error("{0} grid cells would be needed (at most {MAX_CELLS})")]
    TooMany(u64),
    #[error("{0}")]
    Cells(#[from] CellSetError),
}

impl FileSource {
    /// Open `file` for `scene`: it must have been built for this scene (fingerprint), be
    /// complete (not a shard) and hold cells of one regular grid.
    pub fn new(file: PvsFile, scene: &Scene) -> Result<Self, FileSourceError> {
        file.check_scene(scene)?;
        if let Some(sh) = &file.header().shard {
            return Err(FileSourceError::Shard(sh.index, sh.count));
        }
        let cells = file.cells();
        let first = *cells.first().ok_or(FileSourceError::Empty)?;
        let size = first.max.x - first.min.x;
        let tol = 1e-6 * size.abs().max(1.0);
        let (mut x0, mut y0) = (f64::INFINITY, f64::INFINITY);
        let (mut x1, mut y1) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for (i, c) in cells.iter().enumerate() {
            let square = size > 0.0
                && ((c.max.x - c.min.x) - size).abs() <= tol
                && ((c.max.y - c.min.y) - size).abs() <= tol
                && (c.min.z - first.min.z).abs() <= tol
                && (c.max.z - first.max.z).abs() <= tol;
            if !square {
                return Err(FileSourceError::NotAGrid(i, *c, first));
            }
            x0 = x0.min(c.min.x);
            y0 = y0.min(c.min.y);
            x1 = x1.max(c.max.x);
            y1 = y1.max(c.max.y);
        }
        let nx = ((x1 - x0) / size).round();
        let ny = ((y1 - y0) / size).round();
        let total = nx * ny;
        if total.is_nan() || total > MAX_CELLS as f64 {
            return Err(FileSourceError::TooMany(total as u64));
        }
        let grid = CellGrid {
            origin: [x0, y0],
            cell_size_m: size,
            nx: nx as u32,
            ny: ny as u32,
            z_range_m: [first.min.z, first.max.z],
            top_m: scene.bounds.max.z.max(first.max.z),
        };
        let squares = grid.squares();
        let mut index = vec![None; squares.len()];
        for (i, c) in cells.iter().enumerate() {
            let fx = (c.min.x - x0) / size;
            let fy = (c.min.y - y0) / size;
            let (ix, iy) = (fx.round(), fy.round());
            let aligned = (fx - ix).abs() * size <= tol && (fy - iy).abs() * size <= tol;
            let on_grid = aligned && ix < nx && iy < ny;
            match on_grid.then(|| squares.id(ix as u32, iy as u32) as usize) {
                Some(id) if index[id].is_none() => index[id] = Some(i as u32),
                _ => return Err(FileSourceError::NotAGrid(i, *c, first)),
            }
        }
        Ok(FileSource {
            file,
            layout: FileLayout::Grid { grid, index },
            kind: "file",
        })
    }

    /// Open `file` for `scene` on the file's own cells (see [`FileSource`]): it must have
    /// been built for this scene and be complete.
    pub fn cells(file: PvsFile, scene: &Scene) -> Result<Self, FileSourceError> {
        file.check_scene(scene)?;
        if let Some(sh) = &file.header().shard {
            return Err(FileSourceError::Shard(sh.index, sh.count));
        }
        if file.cells().is_empty() {
            return Err(FileSourceError::Empty);
        }
        let set = CellSet::new(file.cells().to_vec())?;
        Ok(FileSource {
            file,
            layout: FileLayout::Cells(set),
            kind: "file",
        })
    }

    /// Say that the file was built at start-up and is held in memory (`/api/scene`'s
    /// `source` is then `"memory"`).
    pub fn in_memory(mut self) -> Self {
        self.kind = "memory";
        self
    }

    /// The file served.
    pub fn file(&self) -> &PvsFile {
        &self.file
    }
}

impl PvsSource for FileSource {
    fn info(&self) -> SourceInfo {
        let h = self.file.header();
        SourceInfo {
            kind: self.kind,
            method: h.method.clone(),
            // `sampled` and `all` are the only non-conservative methods (`all`
            // is conservative, if useless).
            conservative: h.method != "sampled",
            params: h.params.iter().map(|(k, v)| format!("{k}={v}")).collect(),
        }
    }

    fn layout(&self) -> Layout<'_> {
        match &self.layout {
            FileLayout::Grid { grid, .. } => Layout::Grid(grid),
            FileLayout::Cells(set) => Layout::Cells(set),
        }
    }

    fn locate(&self, p: DVec3) -> Result<CellId, PointError> {
        match &self.layout {
            FileLayout::Grid { grid, .. } => grid.locate(p),
            FileLayout::Cells(_) => {
                if !p.is_finite() {
                    return Err(PointError::NotFinite);
                }
                self.file
                    .locate(p)
                    .map(|i| i as CellId)
                    .ok_or(PointError::NoCell(p.x, p.y, p.z))
            }
        }
    }

    fn pvs(&self, id: CellId) -> Result<Vec<u32>, SourceError> {
        let i = match &self.layout {
            FileLayout::Grid { index, .. } => index.get(id as usize).copied().flatten(),
            FileLayout::Cells(set) => ((id as usize) < set.len()).then_some(id),
        }
        .ok_or(SourceError::NoCell(id))?;
        self.file
            .pvs(i as usize)
            .map_err(|e| SourceError::Method(e.to_string()))
    }
}

/// Shared handle.
pub type SharedSource = Arc<dyn PvsSource>;

#[cfg(test)]
mod tests {
    use super::*;
    use sightline_geom::DVec3;
    use sightline_pvs::{build, BuildOptions};
    use sightline_scene::generate::city;

    /// Square 50 m cells over the scene, aligned on multiples of 50 m, minus `skip`.
    fn grid_cells(scene: &Scene, skip: usize) -> Vec<ViewCell> {
        let (b, s) = (scene.bounds, 50.0);
        let (x0, y0) = ((b.min.x / s).floor() * s, (b.min.y / s).floor() * s);
        let mut out = Vec::new();
        let mut y = y0;
        while y < b.max.y {
            let mut x = x0;
            while x < b.max.x {
                out.push(ViewCell {
                    min: DVec3::new(x, y, 1.5),
                    max: DVec3::new(x + s, y + s, 2.0),
                });
                x += s;
            }
            y += s;
        }
        out.remove(skip);
        out
    }

    fn built(scene: &Arc<Scene>, cells: &[ViewCell], name: &str) -> PvsFile {
        let m = sightline_methods::create("dual-ray", scene.clone(), &Default::default()).unwrap();
        let path =
            std::env::temp_dir().join(format!("sightline-{name}-{}.pvs", std::process::id()));
        build(
            scene,
            m.as_ref(),
            cells,
            &path,
            &BuildOptions::default(),
            &|_, _| {},
        )
        .unwrap();
        let f = PvsFile::open(&path).unwrap();
        std::fs::remove_file(&path).ok();
        f
    }

    #[test]
    fn a_file_source_answers_the_file_on_its_grid() {
        let scene = Arc::new(city(3, 80));
        let cells = grid_cells(&scene, 2);
        let file = built(&scene, &cells, "grid");
        let expected: Vec<Vec<u32>> = (0..cells.len()).map(|i| file.pvs(i).unwrap()).collect();
        let src = FileSource::new(file, &scene).unwrap();
        assert_eq!(src.info().kind, "file");
        assert_eq!(src.info().method, "dual-ray");
        assert_eq!(src.layout().len(), cells.len() + 1);
        for (i, c) in cells.iter().enumerate() {
            let id = src.locate(c.center()).unwrap();
            assert_eq!(src.cell(id), Some(*c));
            assert_eq!(src.pvs(id).unwrap(), expected[i]);
        }
        // The grid's cell the file lacks.
        let FileLayout::Grid { index, .. } = &src.layout else {
            panic!("a grid file is served on its grid")
        };
        let missing = (0..src.layout().len() as u32)
            .find(|&id| index[id as usize].is_none())
            .unwrap();
        assert_eq!(missing, 2);
        assert_eq!(src.pvs(missing), Err(SourceError::NoCell(2)));
    }

    #[test]
    fn a_file_of_another_scene_or_not_a_grid_is_refused() {
        let scene = Arc::new(city(3, 80));
        let cells = grid_cells(&scene, 0);
        let other = city(4, 80);
        let err = FileSource::new(built(&scene, &cells, "other"), &other)
            .err()
            .unwrap();
        assert!(matches!(err, FileSourceError::Pvs(_)), "{err}");
        let mut shifted = cells.clone();
        shifted[1].min.x += 10.0;
        shifted[1].max.x += 10.0;
        let err = FileSource::new(built(&scene, &shifted, "shifted"), &scene)
            .err()
            .unwrap();
        assert!(matches!(err, FileSourceError::NotAGrid(1, _, _)), "{err}");
        let mut small = cells;
        small[3].max.y -= 5.0;
        let err = FileSource::new(built(&scene, &small, "small"), &scene)
            .err()
            .unwrap();
        assert!(matches!(err, FileSourceError::NotAGrid(3, _, _)), "{err}");
    }
}

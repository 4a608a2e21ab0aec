//! `query FILE.pvs --can-see A,B | --seen-by X,Y,Z | --secondary CELL`: the gameplay
//! queries of `sightline-runtime` (guarantees in `crates/runtime/src/gameplay.rs`).

use crate::common::print_json;
use anyhow::Context;
use serde::Serialize;
use sightline_runtime::{CellRelation, Pvs, Query};
use std::path::Path;

/// The gameplay questions of one `query` call (at least one is asked).
pub struct Questions {
    pub can_see: Option<[u32; 2]>,
    pub seen_by: Option<[f64; 3]>,
    pub secondary: Option<u32>,
}

#[derive(Serialize)]
struct CanSee {
    a: u32,
    b: u32,
    visible: bool,
}

#[derive(Serialize)]
struct SeenBy {
    at: [f64; 3],
    cell: Option<u32>,
    cells: Vec<u32>,
}

#[derive(Serialize)]
struct Secondary {
    cell: u32,
    visible: Vec<u32>,
}

#[derive(Serialize)]
struct Report {
    /// `leaves` (conservative) or `shared-objects` (conservative in closed scenes).
    relation: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    can_see: Option<CanSee>,
    #[serde(skip_serializing_if = "Option::is_none")]
    seen_by: Option<SeenBy>,
    #[serde(skip_serializing_if = "Option::is_none")]
    secondary: Option<Secondary>,
}

pub fn run(path: &Path, ask: &Questions, json: bool) -> anyhow::Result<()> {
    let pvs = Pvs::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let mut q = Query::new();
    let in_file = |c: u32| {
        anyhow::ensure!(
            pvs.is_stored(c),
            "{} has no cell {c} (cells 0..{}, or not stored in this shard)",
            path.display(),
            pvs.cell_count()
        );
        Ok(())
    };
    let can_see = match ask.can_see {
        Some([a, b]) => {
            in_file(a)?;
            in_file(b)?;
            let visible = pvs.can_see(&mut q, a, b)?;
            Some(CanSee { a, b, visible })
        }
        None => None,
    };
    let seen_by = match ask.seen_by {
        Some(at) => {
            let mut cells = Vec::new();
            let cell = pvs.cells_seeing_point_into(&mut q, at, &mut cells)?;
            Some(SeenBy { at, cell, cells })
        }
        None => None,
    };
    let secondary = match ask.secondary {
        Some(cell) => {
            in_file(cell)?;
            let mut visible = Vec::new();
            pvs.secondary_into(&mut q, cell, &mut visible)?;
            Some(Secondary { cell, visible })
        }
        None => None,
    };
    let report = Report {
        relation: match pvs.cell_relation() {
            CellRelation::Leaves => "leaves",
            CellRelation::SharedObjects => "shared-objects",
        },
        can_see,
        seen_by,
        secondary,
    };
    if json {
        return print_json(&report);
    }
    let list = |ids: &[u32]| ids.iter().map(u32::to_string).collect::<Vec<_>>().join(" ");
    if let Some(c) = &report.can_see {
        let verdict = if c.visible { "may see" } else { "cannot see" };
        println!("cell {} {verdict} cell {} ({})", c.a, c.b, report.relation);
    }
    if let Some(s) = &report.seen_by {
        let [x, y, z] = s.at;
        match s.cell {
            Some(cell) => println!(
                "{} cells may see {x},{y},{z} (cell {cell}): {}",
                s.cells.len(),
                list(&s.cells)
            ),
            None => println!("no cell holds {x},{y},{z}"),
        }
    }
    if let Some(s) = &report.secondary {
        println!(
            "secondary PVS of cell {}: {} objects\n{}",
            s.cell,
            s.visible.len(),
            list(&s.visible)
        );
    }
    Ok(())
}

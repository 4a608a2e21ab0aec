//! One judging harness for every kind: a PVS against an independent truth, reported as
//! missed (seen but not in the PVS, with witnesses), over (PVS / truth) and culled.
//! The truths stay where they are — the item-buffer truth of `sightline-core`
//! (`check`, sampled in a box or in an automatic cell's free voxels) and the BSP ray
//! oracle of `sightline-portals` — the harness gathers their verdicts into one
//! [`Judgement`] and says, once, when a conservative method missed something.

use serde::Serialize;
use sightline_autocells::judge::JudgedCell;
use sightline_core::check::CheckReport;
use sightline_portals::reference::VisReport;

/// One thing the truth saw and the PVS lacks.
#[derive(Clone, Debug, Serialize)]
pub struct Miss {
    /// The judged cell, as its report names it (a box, an automatic cell's index).
    pub cell: serde_json::Value,
    /// The object, cluster or leaf missed.
    pub id: u32,
    /// The sample that saw it, when the truth keeps one.
    pub viewpoint: Option<[f64; 3]>,
    pub direction: Option<[f64; 3]>,
}

/// The truth's own figures behind a [`Judgement`].
#[derive(Clone, Debug)]
pub enum Evidence {
    /// Viewcell boxes of any scene against the item-buffer truth (`check_cells`).
    Boxes(CheckReport),
    /// A mesh level's automatic cells or walkable viewcells against the truth sampled
    /// in their free voxels.
    Cells(Vec<JudgedCell>),
    /// A BSP level's leaf PVS against its own `vis` and the ray oracle (leaf pairs).
    Leaves(VisReport),
}

/// A method's PVS judged against a truth.
#[derive(Clone, Debug)]
pub struct Judgement {
    pub method: String,
    pub conservative: bool,
    /// What one miss counts: "object", "cluster", "leaf pair".
    pub unit: &'static str,
    /// Cells (or source leaves) judged.
    pub judged: usize,
    /// Misses in all (must be 0 for a conservative method).
    pub missed: usize,
    /// The misses that come with a witness.
    pub witnesses: Vec<Miss>,
    /// Median |PVS| / |truth| over the judged cells (BSP: Σ leaves / Σ of `vis`).
    pub over_median: f64,
    /// Median share of the objects a cell culls (over the sizes given).
    pub culled_median: f64,
    pub evidence: Evidence,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

impl Judgement {
    /// Boxes judged by `sightline_core::check` (`check SCENE --method M`, a `.pvs`).
    pub fn of_boxes(report: CheckReport, conservative: bool) -> Judgement {
        let witnesses = report
            .per_cell
            .iter()
            .flat_map(|c| {
                c.missed.iter().map(move |x| Miss {
                    cell: serde_json::to_value(c.cell).unwrap_or_default(),
                    id: x.id,
                    viewpoint: Some(x.viewpoint),
                    direction: Some(x.direction),
                })
            })
            .collect();
        Judgement {
            method: report.method.clone(),
            conservative,
            unit: "object",
            judged: report.cells,
            missed: report.missed,
            witnesses,
            over_median: report.over_median,
            culled_median: median(report.per_cell.iter().map(|c| c.hidden_fraction).collect()),
            evidence: Evidence::Boxes(report),
        }
    }

    /// Automatic cells or walkable viewcells judged in their free voxels; `sizes` are
    /// the PVS sizes the culled share is taken over, of `objects` clusters.
    pub fn of_cells(
        method: &str,
        judged: Vec<JudgedCell>,
        sizes: impl Iterator<Item = usize>,
        objects: usize,
    ) -> Judgement {
        let witnesses = judged
            .iter()
            .flat_map(|j| {
                j.missed.iter().map(move |w| Miss {
                    cell: j.cell.into(),
                    id: w.id,
                    viewpoint: Some(w.viewpoint),
                    direction: Some(w.direction),
                })
            })
            .collect();
        Judgement {
            method: method.to_string(),
            conservative: true,
            unit: "cluster",
            judged: judged.len(),
            missed: judged.iter().map(|j| j.missed.len()).sum(),
            witnesses,
            over_median: median(
                judged
                    .iter()
                    .map(|j| j.pvs as f64 / j.truth.max(1) as f64)
                    .collect(),
            ),
            culled_median: median(
                sizes
                    .map(|n| 1.0 - n as f64 / objects.max(1) as f64)
                    .collect(),
            ),
            evidence: Evidence::Cells(judged),
        }
    }

    /// A BSP level's leaf PVS against its `vis` and the ray oracle.
    pub fn of_leaves(report: VisReport) -> Judgement {
        Judgement {
            method: report.mode.to_string(),
            conservative: true,
            unit: "leaf pair",
            judged: report.sources,
            missed: report.missed_pairs,
            witnesses: Vec::new(),
            over_median: report.leaves_ratio(),
            culled_median: 0.0,
            evidence: Evidence::Leaves(report),
        }
    }

    /// The verdict: an error when a conservative method missed something.
    pub fn verdict(&self) -> anyhow::Result<()> {
        if self.conservative && self.missed > 0 {
            let witnesses = if self.witnesses.is_empty() {
                ""
            } else {
                " (witnesses above)"
            };
            anyhow::bail!(
                "method {} missed {} visible {}(s) — a conservativeness bug{witnesses}",
                self.method,
                self.missed,
                self.unit
            );
        }
        Ok(())
    }
}

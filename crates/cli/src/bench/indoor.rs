//! The indoor section: cells and portals on Quake levels (issue #38). Per level: leaves,
//! portals, the wall time of the fast bound and of the full flow, peak memory, Σ|PVS|
//! against the level's own `vis` for leaves and faces, and misses against the ray
//! oracle — the figures of `check LEVEL.bsp --reference vis`
//! ([`sightline_portals::reference`]), with the solves timed apart. With a reference
//! `vis` (ericw-tools: `bench --vis-reference PATH`, or `vis` on `PATH`), each level is
//! also run through both tools side by side ([`super::vis_reference`]).

use super::plots::{scatter_chart, Series};
use super::report::{Report, Table};
use super::suite::{Suite, NO_REPEAT_MS};
use super::vis_reference::{side_by_side, Reference, SideBySide, ToolRuns, MAX_REPEATS};
use anyhow::Context;
use serde::Serialize;
use sightline_portals::reference::{compare_sets, leaf_sizes, LeafSizes, VisReport};
use sightline_portals::{LeafPvs, Mode, Portals};
use sightline_scene::import::bsp::load_bsp;
use sightline_stats::median;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Oracle segments per pair our PVS calls hidden (256 for pairs the reference has), as
/// `check --reference vis`.
const SEGMENTS: usize = 16;

/// The measured figures of one level.
#[derive(Clone, Debug, Serialize)]
pub struct IndoorRecord {
    pub level: String,
    pub leaves: usize,
    pub visleafs: u32,
    pub portals: usize,
    /// Runs timed (a run whose full solve passes `NO_REPEAT_MS` is not repeated).
    pub runs: usize,
    /// Medians: portals and base flood (`Portals::build`), then the whole fast bound
    /// and the whole full solve, each from a fresh `Portals` (build included).
    pub build_ms: f64,
    pub fast_ms: f64,
    pub full_ms: f64,
    /// The process's peak resident memory while this level ran (MiB; 0 if unknown).
    pub peak_mib: f64,
    pub full: VisReport,
    pub fast: VisReport,
    /// Whether every leaf's fast bound holds its full PVS (leaves and faces).
    pub fast_contains_full: bool,
    /// Per view leaf: our full PVS against the reference (the plot's points).
    pub per_leaf: Vec<LeafSizes>,
    /// `sightline vis` beside the reference `vis`, when one is given.
    pub vis_reference: Option<SideBySide>,
}

/// The `.bsp` files named by `paths`: a file as is, a folder's `*.bsp` sorted by name.
pub fn find_levels(paths: &[PathBuf]) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut v: Vec<PathBuf> = std::fs::read_dir(p)
                .with_context(|| format!("cannot read the folder {}", p.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.extension().is_some_and(|e| e.eq_ignore_ascii_case("bsp")))
                .collect();
            v.sort();
            anyhow::ensure!(!v.is_empty(), "{} holds no .bsp level", p.display());
            out.extend(v);
        } else if p.is_file() {
            out.push(p.clone());
        } else {
            anyhow::bail!("{} is neither a .bsp level nor a folder", p.display());
        }
    }
    Ok(out)
}

/// Reset the process's peak resident size (Linux ≥ 4.0), so the next reading is this
/// level's own peak.
pub(super) fn reset_peak() {
    std::fs::write("/proc/self/clear_refs", "5").ok();
}

pub(super) fn peak_mib() -> f64 {
    sightline_stats::memory_kib().1 as f64 / 1024.0
}

fn contains(big: &[u32], small: &[u32]) -> bool {
    small.iter().all(|x| big.binary_search(x).is_ok())
}

/// Measure one level: `repeats` timed runs at most, `sources` source leaves for the
/// oracle.
pub fn measure_level(path: &Path, repeats: usize, sources: usize) -> anyhow::Result<IndoorRecord> {
    let level = load_bsp(path).with_context(|| format!("cannot load {}", path.display()))?;
    reset_peak();
    let (mut build, mut fast, mut full) = (Vec::new(), Vec::new(), Vec::new());
    let mut solved: Option<(Portals, Vec<LeafPvs>, Vec<LeafPvs>)> = None;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let portals = Portals::build(&level)
            .with_context(|| format!("cannot build the portals of {}", path.display()))?;
        let build_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let fast_sets = portals.solve_all(Mode::Fast);
        let fast_ms = build_ms + t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let full_sets = portals.solve_all(Mode::Full);
        let full_ms = build_ms + t.elapsed().as_secs_f64() * 1e3;
        build.push(build_ms);
        fast.push(fast_ms);
        full.push(full_ms);
        solved = Some((portals, fast_sets, full_sets));
        if full_ms > NO_REPEAT_MS {
            break;
        }
    }
    let Some((portals, fast_sets, full_sets)) = solved else {
        anyhow::bail!("no run of {}", path.display());
    };
    let peak = peak_mib();
    let full_report = compare_sets(&portals, &full_sets, Mode::Full, sources, SEGMENTS);
    let fast_report = compare_sets(&portals, &fast_sets, Mode::Fast, 0, SEGMENTS);
    let fast_contains_full = full_sets.iter().zip(&fast_sets).all(|(a, b)| {
        a.leaf == b.leaf && contains(&b.leaves, &a.leaves) && contains(&b.faces, &a.faces)
    });
    Ok(IndoorRecord {
        level: path.file_stem().map_or_else(
            || path.display().to_string(),
            |s| s.to_string_lossy().into(),
        ),
        leaves: level.leaves.len(),
        visleafs: level.visleafs,
        portals: portals.portals().len(),
        runs: build.len(),
        build_ms: median(&build),
        fast_ms: median(&fast),
        full_ms: median(&full),
        peak_mib: peak,
        per_leaf: leaf_sizes(&level, &full_sets),
        full: full_report,
        fast: fast_report,
        fast_contains_full,
        vis_reference: None,
    })
}

/// Measure the level at `path` into `records` (a failure or a miss becomes a note).
pub fn measure_into(
    suite: &Suite,
    path: &Path,
    records: &mut Vec<IndoorRecord>,
    notes: &mut Vec<String>,
    quiet: bool,
) {
    if !quiet {
        eprintln!("bench: indoor {}", path.display());
    }
    match measure_level(path, suite.timing_repeats, suite.indoor_sources) {
        Ok(r) => {
            if r.full.missed_pairs > 0 {
                notes.push(format!(
                    "`portals` MISSED {} visible leaf pairs on {} (a conservativeness bug)",
                    r.full.missed_pairs, r.level
                ));
            }
            if !r.fast_contains_full {
                notes.push(format!(
                    "`portals-fast` does not contain `portals` on {}",
                    r.level
                ));
            }
            let mut r = r;
            if let Some(vis) = &suite.vis_reference {
                if !quiet {
                    eprintln!("bench: indoor {} beside {}", path.display(), vis.display());
                }
                let reference = Reference {
                    vis: vis.clone(),
                    ours: std::env::current_exe().unwrap_or_else(|_| "sightline".into()),
                    prt_dir: suite.vis_prt.clone(),
                    threads: rayon::current_num_threads(),
                };
                match side_by_side(path, &reference, suite.timing_repeats, suite.indoor_sources) {
                    Ok(s) => {
                        for (who, t) in [
                            ("sightline vis", &s.ours_full),
                            ("sightline vis --fast", &s.ours_fast),
                            ("the reference vis", &s.reference_full),
                            ("the reference vis -fast", &s.reference_fast),
                        ] {
                            if t.misses > 0 {
                                notes.push(format!(
                                    "{who} MISSED {} visible leaf pairs on {}",
                                    t.misses, r.level
                                ));
                            }
                        }
                        r.vis_reference = Some(s);
                    }
                    Err(e) => notes.push(format!("indoor beside vis: {}: {e:#}", path.display())),
                }
            }
            records.push(r);
        }
        Err(e) => notes.push(format!("indoor: {}: {e:#}", path.display())),
    }
}

/// The section of the levels measured: the table, and the plots written into `out`.
pub fn write_section(
    suite: &Suite,
    records: &[IndoorRecord],
    rep: &mut Report,
    out: &Path,
) -> anyhow::Result<()> {
    rep.section("Indoor: cells and portals on Quake levels");
    let threads = rayon::current_num_threads();
    rep.para(&format!(
        "Each level's leaves are its cells (`sightline_portals`). Times are wall times on {threads} rayon threads, the median of up to {} runs (a run whose full solve passes {NO_REPEAT_MS} ms is not repeated), each from a fresh `Portals`: *portals* = portalization and base flood, *fast* = that plus every leaf's `portals-fast` set, *full* = that plus the flow through portal sequences and every leaf's `portals` set. Σ ratios are over every view leaf against the level's own `vis` rows; *faces* is our faces over the faces of the leaves `vis` sees. The oracle traces random segments from {} source leaves to every leaf our PVS lacks ({SEGMENTS} per pair, 256 for pairs `vis` has): *missed* must be 0. Peak memory is the process's high-water mark while the level ran.",
        suite.timing_repeats, suite.indoor_sources
    ));
    let mut t = Table::new(&[
        "level",
        "leaves",
        "visleafs",
        "portals",
        "runs",
        "portals ms",
        "fast ms",
        "full ms",
        "peak MiB",
        "Σ leaves full / vis",
        "Σ leaves fast / vis",
        "faces full / vis-leaf faces",
        "faces fast / vis-leaf faces",
        "fast ⊇ full",
        "sources",
        "missed",
        "vis-only pairs (clear)",
    ]);
    for r in records {
        t.row(vec![
            r.level.clone(),
            r.leaves.to_string(),
            r.visleafs.to_string(),
            r.portals.to_string(),
            r.runs.to_string(),
            format!("{:.0}", r.build_ms),
            format!("{:.0}", r.fast_ms),
            format!("{:.0}", r.full_ms),
            format!("{:.0}", r.peak_mib),
            format!("{:.3}", r.full.leaves_ratio()),
            format!("{:.3}", r.fast.leaves_ratio()),
            format!("{:.3}", r.full.faces_ratio()),
            format!("{:.3}", r.fast.faces_ratio()),
            if r.fast_contains_full { "yes" } else { "NO" }.into(),
            r.full.sources.to_string(),
            r.full.missed_pairs.to_string(),
            format!(
                "{} ({})",
                r.full.reference_only_pairs, r.full.reference_only_clear
            ),
        ]);
    }
    rep.table(&t);
    if records.is_empty() {
        return Ok(());
    }
    let series = |faces: bool| -> Vec<Series> {
        records
            .iter()
            .map(|r| Series {
                name: r.level.clone(),
                points: r
                    .per_leaf
                    .iter()
                    .map(|s| {
                        if faces {
                            (s.faces_reference as f64, s.faces_ours as f64)
                        } else {
                            (s.leaves_reference as f64, s.leaves_ours as f64)
                        }
                    })
                    .collect(),
            })
            .collect()
    };
    scatter_chart(
        &out.join("indoor-leaves.png"),
        "portals: |PVS| per leaf against vis (leaves)",
        "leaves in the vis row",
        "leaves in our PVS",
        &series(false),
    )?;
    rep.image("indoor-leaves.png", "leaf PVS size per leaf against vis");
    scatter_chart(
        &out.join("indoor-faces.png"),
        "portals: faces per leaf against the faces of vis's leaves",
        "faces of the leaves vis sees",
        "faces in our PVS",
        &series(true),
    )?;
    rep.image("indoor-faces.png", "face PVS size per leaf against vis");
    rep.para(
        "One point per view leaf; below the line y = x our set is smaller than the reference's.",
    );
    write_side_by_side(records, rep, out)
}

/// Seconds with two decimals, or `-`.
fn secs(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.2}"))
}

/// Σ of a tool's rows over the shipped Σ; the range when its runs differ.
fn sum_ratio(s: &SideBySide, t: &ToolRuns) -> String {
    let (lo, hi) = t.sums();
    let shipped = s.shipped_sum.max(1) as f64;
    let (lo, hi) = (
        format!("{:.4}", lo as f64 / shipped),
        format!("{:.4}", hi as f64 / shipped),
    );
    if lo == hi {
        format!("{:.4}", s.ratio(t))
    } else {
        format!("{lo}–{hi}")
    }
}

/// The table and plots of the levels run beside a reference `vis` (nothing without one).
fn write_side_by_side(
    records: &[IndoorRecord],
    rep: &mut Report,
    out: &Path,
) -> anyhow::Result<()> {
    let sides: Vec<(&str, &SideBySide)> = records
        .iter()
        .filter_map(|r| Some((r.level.as_str(), r.vis_reference.as_ref()?)))
        .collect();
    let Some((_, first)) = sides.first() else {
        return Ok(());
    };
    rep.section("Indoor: beside ericw-tools `vis`");
    rep.para(&format!(
        "Per level, in this run on this machine: the reference `vis` (`-threads {t}`) and `sightline vis` (`--threads {t}`, this binary) each on a fresh copy of the level and from the same `.prt` ({prt}), alternating (reference full, ours full, reference `-fast`, ours `--fast`; up to {MAX_REPEATS} rounds as the suite repeats). Wall time is measured by the bench, CPU time (user + system) and peak resident memory by {timer}; times are medians over the rounds, peak memory the largest. Σ is Σ|row| of the rows each tool wrote (read back from the visibility lump) over Σ|row| of the rows the level shipped with (1996), a range when the runs differ. *Misses* are the ray oracle's on the first round's rows: {src} source leaves spread evenly, each against every view leaf its row lacks, 16 random segments per pair (0 is required). *Load* is the one-minute load average before the level's first run → after its last.",
        t = first.threads,
        timer = if first.timer == "GNU time" { "GNU `time`" } else { "nothing (no `/usr/bin/time`: wall time only)" },
        src = first.sources,
        prt = if first.prt.starts_with("shared") { "`--vis-prt`'s `LEVEL.prt` where it has one: *shared*" } else { "our own portals written as PRT1: *ours (written)*" },
    ));
    let mut t = Table::new(&[
        "level",
        ".prt (portals)",
        "rounds",
        "load",
        "vis wall s",
        "ours wall s",
        "vis CPU s",
        "ours CPU s",
        "vis peak MiB",
        "ours peak MiB",
        "Σ vis / 1996",
        "Σ ours / 1996",
        "misses vis / ours",
        "vis -fast wall s",
        "ours --fast wall s",
        "vis -fast CPU s",
        "ours --fast CPU s",
        "Σ fast vis / ours",
        "misses fast vis / ours",
    ]);
    for (level, s) in &sides {
        let peak = |t: &ToolRuns| {
            t.peak_mib()
                .map_or_else(|| "-".into(), |m| format!("{m:.1}"))
        };
        t.row(vec![
            level.to_string(),
            format!("{} ({})", s.prt, s.portals),
            s.ours_full.runs.len().to_string(),
            format!("{:.1} → {:.1}", s.load[0], s.load[1]),
            format!("{:.2}", s.reference_full.wall_s()),
            format!("{:.2}", s.ours_full.wall_s()),
            secs(s.reference_full.cpu_s()),
            secs(s.ours_full.cpu_s()),
            peak(&s.reference_full),
            peak(&s.ours_full),
            sum_ratio(s, &s.reference_full),
            sum_ratio(s, &s.ours_full),
            format!("{} / {}", s.reference_full.misses, s.ours_full.misses),
            format!("{:.2}", s.reference_fast.wall_s()),
            format!("{:.2}", s.ours_fast.wall_s()),
            secs(s.reference_fast.cpu_s()),
            secs(s.ours_fast.cpu_s()),
            format!(
                "{} / {}",
                sum_ratio(s, &s.reference_fast),
                sum_ratio(s, &s.ours_fast)
            ),
            format!("{} / {}", s.reference_fast.misses, s.ours_fast.misses),
        ]);
    }
    rep.table(&t);
    let series = |fast: bool| -> Vec<Series> {
        sides
            .iter()
            .map(|(level, s)| {
                let (a, b) = if fast {
                    (&s.reference_fast, &s.ours_fast)
                } else {
                    (&s.reference_full, &s.ours_full)
                };
                Series {
                    name: level.to_string(),
                    points: a
                        .runs
                        .iter()
                        .zip(&b.runs)
                        .map(|(a, b)| (a.wall_s, b.wall_s))
                        .collect(),
                }
            })
            .collect()
    };
    scatter_chart(
        &out.join("indoor-vis-time.png"),
        "full vis: wall time, ours against ericw-tools (each round)",
        "ericw-tools vis, s",
        "sightline vis, s",
        &series(false),
    )?;
    rep.image(
        "indoor-vis-time.png",
        "full vis wall time, ours against ericw-tools",
    );
    scatter_chart(
        &out.join("indoor-vis-fast-time.png"),
        "fast bound: wall time, ours against ericw-tools -fast (each round)",
        "ericw-tools vis -fast, s",
        "sightline vis --fast, s",
        &series(true),
    )?;
    rep.image(
        "indoor-vis-fast-time.png",
        "fast bound wall time, ours against ericw-tools",
    );
    rep.para("One point per level and round (the pair run one after the other); below the line y = x ours was faster.");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::machine::Machine;

    /// The section on dm1 (the smallest level): its facts, no miss, the fast bound
    /// holds the full sets, the table and both plots are written.
    #[test]
    fn indoor_section_on_dm1() {
        let dm1 = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/quake/dm1.bsp");
        let mut suite = Suite::named("quick").unwrap();
        suite.timing_repeats = 1;
        suite.indoor_sources = 4;
        let dir = tempfile::tempdir().unwrap();
        let mut rep = Report::new(&suite, &Machine::detect());
        let (mut records, mut notes) = (Vec::new(), Vec::new());
        for level in find_levels(&[dm1]).unwrap() {
            measure_into(&suite, &level, &mut records, &mut notes, true);
        }
        write_section(&suite, &records, &mut rep, dir.path()).unwrap();
        assert!(notes.is_empty(), "{notes:?}");
        let r = &records[0];
        assert_eq!((r.level.as_str(), r.visleafs), ("dm1", 434));
        assert!(r.portals > 1000 && r.runs == 1);
        assert!(r.full_ms >= r.build_ms && r.fast_ms >= r.build_ms);
        assert_eq!((r.full.sources, r.full.missed_pairs), (4, 0));
        assert!(r.fast_contains_full);
        assert!(r.full.leaves_ratio() > 0.5 && r.full.leaves_ratio() <= r.fast.leaves_ratio());
        assert!(r.full.faces_ratio() < 1.0);
        assert_eq!(r.per_leaf.len(), 434);
        let md = rep.markdown();
        assert!(md.contains("| dm1 | 483 | 434 |"), "{md}");
        for png in ["indoor-leaves.png", "indoor-faces.png"] {
            let img = image::open(dir.path().join(png)).unwrap();
            assert_eq!(img.width(), 900);
        }
        assert!(find_levels(&[dir.path().to_path_buf()]).is_err());
        assert!(find_levels(&[dir.path().join("none.bsp")]).is_err());
    }
}

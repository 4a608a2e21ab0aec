//! The indoor section beside a reference `vis` (ericw-tools, issue #49): per level, in
//! the same run on the same machine and from the same `.prt`, the reference's `vis`
//! and `sightline vis` each run on a copy of the level, alternating (reference full,
//! ours full, reference `-fast`, ours `--fast`, and again for every repeat), both on
//! the same number of threads. Each run is a child process: wall time, CPU time
//! (user + system) and peak resident memory from GNU `time` when `/usr/bin/time` is
//! there (wall time only otherwise). The rows each tool wrote are read back from the
//! level's visibility lump: Σ|row| against the rows the level shipped with, and misses
//! against the ray oracle (clear segments to a leaf a row lacks).
//!
//! The `.prt` is the shared one when a folder of them is given (`LEVEL.prt`), else our
//! own portals written by [`sightline_portals::prt::prt_from_portals`].

use anyhow::Context;
use serde::Serialize;
use sightline_portals::oracle::{pair_visible, sample_leaf, Rng};
use sightline_portals::portalize::portalize;
use sightline_portals::prt::{parse_prt, prt_from_portals};
use sightline_scene::import::bsp::{load_bsp, BspLevel};
use sightline_stats::median;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// GNU `time`, when present: CPU time and peak memory of each child.
const GNU_TIME: &str = "/usr/bin/time";
/// Oracle segments per (source, leaf the row lacks) pair, as the `vis_rows` example.
const SEGMENTS: usize = 16;
/// Runs of each tool and mode at most (the suite's repeats, capped: a full vis of a
/// large level takes tens of seconds on a loaded 2-core machine).
pub const MAX_REPEATS: usize = 3;

/// The tools to run side by side.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The reference `vis` (ericw-tools).
    pub vis: PathBuf,
    /// Our `sightline` executable (its `vis` command).
    pub ours: PathBuf,
    /// A folder of `LEVEL.prt` files to start from; our own written portals otherwise.
    pub prt_dir: Option<PathBuf>,
    /// Threads of both tools (`-threads N`, `--threads N`).
    pub threads: usize,
}

/// One timed run of one tool.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Run {
    pub wall_s: f64,
    /// User + system CPU seconds (`None`: no GNU `time`).
    pub cpu_s: Option<f64>,
    /// Peak resident memory (MiB; `None`: no GNU `time`).
    pub peak_mib: Option<f64>,
    /// Σ|row| over the level's visleafs of the rows it wrote.
    pub sum: usize,
}

/// Every run of one tool in one mode, and the oracle's misses on the first run's rows.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ToolRuns {
    pub runs: Vec<Run>,
    pub misses: usize,
}

impl ToolRuns {
    pub fn wall_s(&self) -> f64 {
        median(&self.runs.iter().map(|r| r.wall_s).collect::<Vec<_>>())
    }
    pub fn cpu_s(&self) -> Option<f64> {
        let v: Option<Vec<f64>> = self.runs.iter().map(|r| r.cpu_s).collect();
        v.filter(|v| !v.is_empty()).map(|v| median(&v))
    }
    pub fn peak_mib(&self) -> Option<f64> {
        self.runs.iter().filter_map(|r| r.peak_mib).reduce(f64::max)
    }
    /// Smallest and largest Σ over the runs (the reference is not deterministic on
    /// several threads).
    pub fn sums(&self) -> (usize, usize) {
        let s = self.runs.iter().map(|r| r.sum);
        (s.clone().min().unwrap_or(0), s.max().unwrap_or(0))
    }
}

/// One level beside the reference.
#[derive(Clone, Debug, Serialize)]
pub struct SideBySide {
    /// Where the portals came from: `shared LEVEL.prt` (from `Reference::prt_dir`) or
    /// `ours (written)`.
    pub prt: String,
    pub portals: usize,
    pub threads: usize,
    /// `GNU time` or `wall only`.
    pub timer: String,
    /// Σ|row| of the rows the level shipped with.
    pub shipped_sum: usize,
    /// Oracle source leaves per check.
    pub sources: usize,
    /// One-minute load average before the level's first run and after its last.
    pub load: [f64; 2],
    pub reference_full: ToolRuns,
    pub ours_full: ToolRuns,
    pub reference_fast: ToolRuns,
    pub ours_fast: ToolRuns,
}

impl SideBySide {
    /// Σ of a tool's rows (the median run's when they differ) over the shipped Σ.
    pub fn ratio(&self, t: &ToolRuns) -> f64 {
        let mut s: Vec<f64> = t.runs.iter().map(|r| r.sum as f64).collect();
        if s.is_empty() {
            return f64::NAN;
        }
        s.sort_by(f64::total_cmp);
        s[s.len() / 2] / self.shipped_sum.max(1) as f64
    }
}

/// `vis` on `PATH` if it is ericw-tools' (its binary names the project; another `vis`,
/// such as the text editor, is not run).
pub fn detect_on_path() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("vis"))
        .find(|p| p.is_file())
        .filter(|p| is_ericw_vis(p))
}

/// Whether the executable at `p` is ericw-tools' `vis` (its bytes name the project).
pub fn is_ericw_vis(p: &Path) -> bool {
    std::fs::read(p).is_ok_and(|b| b.windows(11).any(|w| w == b"ericw-tools"))
}

/// The one-minute load average (0 if unknown).
pub fn load_average() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0.0)
}

/// GNU `time -f "%e %U %S %M"` output: (user + system CPU s, peak MiB) from its last
/// line (a failed command adds a line before it).
pub fn parse_gnu_time(text: &str) -> Option<(f64, f64)> {
    let line = text.lines().rev().find(|l| !l.trim().is_empty())?;
    let v: Vec<f64> = line
        .split_whitespace()
        .map(|x| x.parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()?;
    let [_wall, user, sys, kib] = v[..] else {
        return None;
    };
    Some((user + sys, kib / 1024.0))
}

/// Σ|row| over visleafs `1..=visleafs` of the level's visibility rows.
pub fn rows_sum(level: &BspLevel) -> usize {
    (1..=level.visleafs)
        .map(|l| level.reference_row(l).len())
        .sum()
}

/// Misses of the level's own rows against the ray oracle: `sources` view leaves spread
/// evenly, each against every view leaf its row lacks, [`SEGMENTS`] random segments
/// between 12 points of each leaf per pair (the `vis_rows` example's check).
pub fn row_misses(level: &BspLevel, sources: usize) -> usize {
    let view: Vec<u32> = (1..=level.visleafs)
        .filter(|&l| level.is_view_leaf(l))
        .collect();
    if view.is_empty() || sources == 0 {
        return 0;
    }
    let mut rng = Rng::new(49);
    let points: Vec<Vec<[f64; 3]>> = (0..level.leaves.len() as u32)
        .map(|l| sample_leaf(level, l, 12, &mut rng))
        .collect();
    let step = (view.len() / sources).max(1);
    let mut misses = 0;
    for &s in view.iter().step_by(step).take(sources) {
        let row = level.reference_row(s);
        for &t in &view {
            if row.binary_search(&t).is_err()
                && pair_visible(
                    level,
                    &points[s as usize],
                    &points[t as usize],
                    SEGMENTS,
                    &mut rng,
                )
            {
                misses += 1;
            }
        }
    }
    misses
}

/// A folder removed when dropped.
struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.0).ok();
    }
}

/// Run `cmd` (its output to `log`), timed.
fn timed(cmd: Command, log: &Path, gnu_time: bool) -> anyhow::Result<Run> {
    let out = std::fs::File::create(log)?;
    let times = log.with_extension("time");
    let mut run = if gnu_time {
        let mut t = Command::new(GNU_TIME);
        t.arg("-f")
            .arg("%e %U %S %M")
            .arg("-o")
            .arg(&times)
            .arg(cmd.get_program())
            .args(cmd.get_args());
        if let Some(d) = cmd.get_current_dir() {
            t.current_dir(d);
        }
        t
    } else {
        cmd
    };
    let t = Instant::now();
    let status = run
        .stdin(Stdio::null())
        .stdout(out.try_clone()?)
        .stderr(out)
        .status()
        .with_context(|| format!("cannot run {:?}", run.get_program()))?;
    let wall_s = t.elapsed().as_secs_f64();
    if !status.success() {
        let text = std::fs::read_to_string(log).unwrap_or_default();
        let last = text.lines().rev().find(|l| !l.trim().is_empty());
        anyhow::bail!(
            "{} failed ({status}): {}",
            run.get_args()
                .map(|a| a.to_string_lossy())
                .collect::<Vec<_>>()
                .join(" "),
            last.unwrap_or("no output")
        );
    }
    let (cpu_s, peak_mib) = if gnu_time {
        std::fs::read_to_string(&times)
            .ok()
            .and_then(|s| parse_gnu_time(&s))
            .map_or((None, None), |(c, m)| (Some(c), Some(m)))
    } else {
        (None, None)
    };
    Ok(Run {
        wall_s,
        cpu_s,
        peak_mib,
        sum: 0,
    })
}

/// The level at `path` beside the reference: `repeats` alternating rounds (at most
/// [`MAX_REPEATS`]), the oracle from `sources` source leaves on each tool's first rows.
pub fn side_by_side(
    path: &Path,
    r: &Reference,
    repeats: usize,
    sources: usize,
) -> anyhow::Result<SideBySide> {
    let shipped = load_bsp(path).with_context(|| format!("cannot load {}", path.display()))?;
    let bsp = std::fs::read(path)?;
    let stem = path
        .file_stem()
        .map_or_else(|| "level".into(), |s| s.to_string_lossy().to_string());
    let shared = r
        .prt_dir
        .as_ref()
        .map(|d| d.join(format!("{stem}.prt")))
        .filter(|p| p.is_file());
    let (prt_bytes, prt_label) = match &shared {
        Some(p) => (std::fs::read(p)?, format!("shared `{stem}.prt`")),
        None => {
            let prt = prt_from_portals(&portalize(&shipped), shipped.visleafs)
                .with_context(|| format!("cannot write the portals of {}", path.display()))?;
            (prt.to_text().into_bytes(), "ours (written)".to_string())
        }
    };
    let portals = parse_prt(&prt_bytes)
        .with_context(|| format!("cannot read the .prt of {}", path.display()))?
        .portals
        .len();
    let dir = TempDir(std::env::temp_dir().join(format!(
        "sightline-vis-reference-{}-{stem}",
        std::process::id()
    )));
    let (ref_dir, our_dir) = (dir.0.join("reference"), dir.0.join("ours"));
    std::fs::create_dir_all(&ref_dir)?;
    std::fs::create_dir_all(&our_dir)?;
    let prt_path = ref_dir.join(format!("{stem}.prt"));
    std::fs::write(&prt_path, &prt_bytes)?;
    let gnu_time = Path::new(GNU_TIME).is_file();
    let threads = r.threads.max(1).to_string();

    let load_before = load_average();
    let mut out: [ToolRuns; 4] = Default::default();
    for round in 0..repeats.clamp(1, MAX_REPEATS) {
        for fast in [false, true] {
            // The reference: the level and its .prt side by side, no state file.
            let level = ref_dir.join(format!("{stem}.bsp"));
            std::fs::write(&level, &bsp)?;
            std::fs::remove_file(ref_dir.join(format!("{stem}.vis"))).ok();
            let mut cmd = Command::new(&r.vis);
            cmd.arg("-threads").arg(&threads);
            if fast {
                cmd.arg("-fast");
            }
            cmd.arg(&level).current_dir(&ref_dir);
            let mut run = timed(cmd, &ref_dir.join("log"), gnu_time)
                .with_context(|| format!("reference vis on {stem}"))?;
            let written = load_bsp(&level)
                .with_context(|| format!("the reference's {stem}.bsp does not load"))?;
            run.sum = rows_sum(&written);
            let slot = &mut out[usize::from(fast) * 2];
            if round == 0 {
                slot.misses = row_misses(&written, sources);
            }
            slot.runs.push(run);

            // Ours, on the same .prt.
            let level = our_dir.join(format!("{stem}.bsp"));
            std::fs::write(&level, &bsp)?;
            std::fs::remove_file(our_dir.join(format!("{stem}.vis-state"))).ok();
            let mut cmd = Command::new(&r.ours);
            cmd.arg("vis")
                .arg(&level)
                .arg("--prt")
                .arg(&prt_path)
                .arg("--threads")
                .arg(&threads)
                .arg("--in-place")
                .arg("--quiet");
            if fast {
                cmd.arg("--fast");
            }
            let mut run = timed(cmd, &our_dir.join("log"), gnu_time)
                .with_context(|| format!("sightline vis on {stem}"))?;
            let written =
                load_bsp(&level).with_context(|| format!("our {stem}.bsp does not load"))?;
            run.sum = rows_sum(&written);
            let slot = &mut out[usize::from(fast) * 2 + 1];
            if round == 0 {
                slot.misses = row_misses(&written, sources);
            }
            slot.runs.push(run);
        }
    }
    let [reference_full, ours_full, reference_fast, ours_fast] = out;
    Ok(SideBySide {
        prt: prt_label,
        portals,
        threads: r.threads.max(1),
        timer: if gnu_time { "GNU time" } else { "wall only" }.into(),
        shipped_sum: rows_sum(&shipped),
        sources,
        load: [load_before, load_average()],
        reference_full,
        ours_full,
        reference_fast,
        ours_fast,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gnu_time_output_parses() {
        assert_eq!(
            parse_gnu_time("6.48 10.5 0.34 12800\n"),
            Some((10.84, 12.5))
        );
        assert_eq!(
            parse_gnu_time("Command exited with non-zero status 1\n0.00 0.00 0.00 2048\n"),
            Some((0.0, 2.0))
        );
        assert_eq!(parse_gnu_time(""), None);
        assert_eq!(parse_gnu_time("1 2 x 4"), None);
        assert_eq!(parse_gnu_time("1 2 3"), None);
    }

    #[test]
    fn medians_sums_and_ratios() {
        let run = |w: f64, c: Option<f64>, m: Option<f64>, sum| Run {
            wall_s: w,
            cpu_s: c,
            peak_mib: m,
            sum,
        };
        let t = ToolRuns {
            runs: vec![
                run(3.0, Some(2.0), Some(10.0), 1010),
                run(1.0, Some(1.0), Some(12.0), 1014),
                run(2.0, Some(5.0), Some(11.0), 1012),
            ],
            misses: 0,
        };
        assert_eq!(t.wall_s(), 2.0);
        assert_eq!(t.cpu_s(), Some(2.0));
        assert_eq!(t.peak_mib(), Some(12.0));
        assert_eq!(t.sums(), (1010, 1014));
        let wall_only = ToolRuns {
            runs: vec![run(1.0, None, None, 5)],
            misses: 0,
        };
        assert_eq!((wall_only.cpu_s(), wall_only.peak_mib()), (None, None));
        let s = SideBySide {
            prt: "ours (written)".into(),
            portals: 1,
            threads: 2,
            timer: "GNU time".into(),
            shipped_sum: 1000,
            sources: 1,
            load: [0.0; 2],
            reference_full: t.clone(),
            ours_full: wall_only,
            reference_fast: ToolRuns::default(),
            ours_fast: ToolRuns::default(),
        };
        assert!((s.ratio(&t) - 1.012).abs() < 1e-12);
        assert!(s.ratio(&ToolRuns::default()).is_nan());
    }

    #[test]
    fn only_ericw_vis_is_taken_for_the_reference() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        std::fs::write(&a, b"\x7fELF ... ---- vis / ericw-tools 2.0.0 ----").unwrap();
        std::fs::write(&b, b"\x7fELF a text editor").unwrap();
        assert!(is_ericw_vis(&a));
        assert!(!is_ericw_vis(&b));
        assert!(!is_ericw_vis(&dir.path().join("none")));
    }

    /// The whole run on dm1 with stand-ins for both tools that leave the level's rows
    /// as shipped: every run is timed, Σ equals the shipped Σ, the shipped rows miss
    /// nothing, the .prt is ours when no folder is given, and a failing tool is an
    /// error naming it.
    #[test]
    fn side_by_side_with_stand_ins_on_dm1() {
        use std::os::unix::fs::PermissionsExt;
        let dm1 = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/quake/dm1.bsp");
        let dir = tempfile::tempdir().unwrap();
        let script = |name: &str, body: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, format!("#!/bin/sh\n{body}\n")).unwrap();
            std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
            p
        };
        let ok = script("ok", "exit 0");
        let r = Reference {
            vis: ok.clone(),
            ours: ok.clone(),
            prt_dir: None,
            threads: 2,
        };
        let s = side_by_side(&dm1, &r, 2, 3).unwrap();
        assert_eq!(
            (s.prt.as_str(), s.portals, s.threads),
            ("ours (written)", 1108, 2)
        );
        assert_eq!(s.sources, 3);
        for t in [
            &s.reference_full,
            &s.ours_full,
            &s.reference_fast,
            &s.ours_fast,
        ] {
            assert_eq!(t.runs.len(), 2);
            assert_eq!(t.misses, 0);
            assert_eq!(t.sums(), (s.shipped_sum, s.shipped_sum));
            assert!(t.wall_s() >= 0.0);
            assert_eq!(t.cpu_s().is_some(), s.timer == "GNU time");
        }
        assert_eq!(s.ratio(&s.ours_full), 1.0);
        // The shared .prt when the folder holds one.
        let prt_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/quake");
        let r = Reference {
            prt_dir: Some(prt_dir),
            ..r
        };
        let s = side_by_side(&dm1, &r, 1, 0).unwrap();
        assert!(s.prt.starts_with("shared"), "{}", s.prt);
        assert_eq!(s.reference_full.runs.len(), 1);
        let bad = script("bad", "echo 'error: no such level' >&2; exit 3");
        let r = Reference { vis: bad, ..r };
        let e = format!("{:#}", side_by_side(&dm1, &r, 1, 0).unwrap_err());
        assert!(
            e.contains("reference vis on dm1") && e.contains("no such level"),
            "{e}"
        );
    }
}

//! `sightline vis LEVEL.bsp [--prt LEVEL.prt] [--fast] [--threads N] [--in-place]`:
//! the leaf PVS of a Quake level written into its visibility lump, as Quake's `vis`
//! does (SPEC §12).
//!
//! * The solver is the portal flow (`portals`; `--fast`: the flood bound
//!   `portals-fast`) on the tree's portals, or on qbsp's `.prt` with `--prt`.
//! * The output is written atomically (a temporary file, then a rename) only once
//!   everything is computed and re-read: a failure at any step leaves the level as it
//!   was. The original is kept as `LEVEL.bsp.orig` (never overwritten: a second run
//!   keeps the first original) unless `--in-place`.
//! * **Resume.** The full flow runs its directed portals in a fixed order, cut into
//!   waves ([`sightline_portals::flow::flow_waves`]); once a wave and all before it are
//!   done its results are appended to `LEVEL.vis-state` (with a fingerprint of the
//!   level's and the `.prt`'s bytes, the mode and the tool's version, and a checksum per
//!   wave). A later run on the same inputs takes the complete leading waves from it and
//!   computes the rest; since a flow only uses the results of flows a fixed distance
//!   before it in the order ([`sightline_portals::flow::FLOW_WINDOW`]), the output is
//!   byte-identical to an uninterrupted run's, and to a run on any number of threads. The state file
//!   is removed once the level is written. `--fast` (well under a second) keeps no
//!   state.

use crate::common::progress;
use anyhow::{bail, Context};
use sightline_portals::bits::Bits;
use sightline_portals::flow::{self, Seen};
use sightline_portals::prt::parse_prt;
use sightline_portals::vislump::{self, Lumps};
use sightline_portals::{Mode, Portals};
use sightline_scene::import::bsp::read_bsp;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct VisArgs {
    /// The level (`.bsp`: Quake's BSP29, or BSP2 / 2PSB).
    pub level: PathBuf,
    /// Start from qbsp's portal file (PRT1) instead of portalizing the level's tree.
    #[arg(long)]
    pub prt: Option<PathBuf>,
    /// The flood bound (`portals-fast`): cheap and looser, as `vis -fast`.
    #[arg(long)]
    pub fast: bool,
    /// Worker threads (default: every core). The output does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Rewrite the level without keeping `LEVEL.bsp.orig`.
    #[arg(long)]
    pub in_place: bool,
    /// Testing: stop with an error after this many flow waves (the state file keeps
    /// them), as an interrupted run would.
    #[arg(long, hide = true)]
    pub stop_after_waves: Option<usize>,
}

pub fn run(args: VisArgs, quiet: bool) -> anyhow::Result<()> {
    let threads = match args.threads {
        Some(0) => bail!("--threads must be at least 1"),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot start the worker threads")?;
    pool.install(|| vis(&args, threads, quiet))
}

fn vis(args: &VisArgs, threads: usize, quiet: bool) -> anyhow::Result<()> {
    let t = Instant::now();
    let path = &args.level;
    let data = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let dir = Lumps::read(&data).with_context(|| format!("cannot use {}", path.display()))?;
    let (visleafs, _) = dir
        .leaf_counts(&data)
        .with_context(|| format!("cannot use {}", path.display()))?;
    let level = read_bsp(&data).with_context(|| format!("cannot load {}", path.display()))?;
    let mode = if args.fast { Mode::Fast } else { Mode::Full };
    let (portals, prt_bytes) = match &args.prt {
        Some(p) => {
            let bytes = std::fs::read(p).with_context(|| format!("cannot read {}", p.display()))?;
            let file = parse_prt(&bytes).with_context(|| format!("cannot use {}", p.display()))?;
            let portals = Portals::from_prt(&level, &file)
                .with_context(|| format!("cannot use {} with {}", p.display(), path.display()))?;
            (portals, Some(bytes))
        }
        None => (
            Portals::build(&level).context("cannot build the level's portals")?,
            None,
        ),
    };

    let mut resumed = 0;
    let state_path = state_path(path);
    let sets: Vec<Bits> = match mode {
        Mode::Fast => portals.visleaf_sets(portals.portal_sets(Mode::Fast)),
        Mode::Full => {
            let fingerprint = fingerprint(&data, prt_bytes.as_deref(), mode);
            let (flows, r) = full_flow(
                &portals,
                &state_path,
                fingerprint,
                args.stop_after_waves,
                quiet,
            )?;
            resumed = r;
            portals.visleaf_sets(&flows)
        }
    };
    let rows: Vec<Vec<u8>> = sets
        .iter()
        .map(|s| vislump::row_of(s.ones().map(|l| l as u32), visleafs))
        .collect();
    let out = vislump::write_vis(&data, &rows)
        .with_context(|| format!("cannot write the visibility of {}", path.display()))?;

    // Read back what an engine reads before replacing anything.
    let back = vislump::read_rows(&out).context("the written level does not read back")?;
    if back.len() != rows.len() || back.iter().zip(&rows).any(|(b, r)| b.as_ref() != Some(r)) {
        bail!("the written visibility rows do not read back (a bug)");
    }
    read_bsp(&out).context("the written level does not load back (a bug)")?;

    let sum: usize = sets.iter().map(|s| s.count()).sum();
    let before = previous_sum(&data);
    let old_lump = dir.lumps[4].1;
    let new_lump = vislump::Lumps::read(&out)
        .map(|d| d.lumps[4].1)
        .unwrap_or(0);

    let orig = orig_path(path);
    let mut kept = "";
    if !args.in_place {
        if orig.exists() {
            kept = " (kept the existing .orig)";
        } else {
            write_atomic(&orig, &data)
                .with_context(|| format!("cannot keep the original as {}", orig.display()))?;
        }
    }
    write_atomic(path, &out).with_context(|| format!("cannot write {}", path.display()))?;
    let _ = std::fs::remove_file(&state_path);

    let ratio = match before {
        Some(b) if b > 0 => format!(" = {:.4} × the previous rows ({b})", sum as f64 / b as f64),
        _ => " (the level had no rows)".to_string(),
    };
    let resumed = if resumed > 0 {
        format!(", {resumed} portal flows resumed")
    } else {
        String::new()
    };
    let source = match &args.prt {
        Some(p) => format!("from {}", p.display()),
        None => "from the tree".to_string(),
    };
    println!(
        "vis {}: method {}, {} portals {source}, {visleafs} visleafs, Σ|PVS| {sum}{ratio}; visibility lump {old_lump} → {new_lump} bytes; {threads} threads, {:.2} s{resumed}{}",
        path.display(),
        if args.fast { "portals-fast" } else { "portals" },
        portals.portals().len(),
        t.elapsed().as_secs_f64(),
        if args.in_place {
            String::new()
        } else {
            format!("; original in {}{kept}", orig.display())
        },
    );
    Ok(())
}

/// Write `bytes` to `path` through a temporary file and a rename; on failure the
/// temporary file is removed, so nothing half-written is left.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), sightline_pvs::PvsError> {
    sightline_pvs::build::write_atomic(path, bytes).inspect_err(|_| {
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(".tmp");
        let _ = std::fs::remove_file(PathBuf::from(tmp));
    })
}

/// `LEVEL.bsp.orig`.
pub fn orig_path(level: &Path) -> PathBuf {
    let mut s = level.as_os_str().to_owned();
    s.push(".orig");
    PathBuf::from(s)
}

/// `LEVEL.vis-state` beside `LEVEL.bsp`.
pub fn state_path(level: &Path) -> PathBuf {
    level.with_extension("vis-state")
}

/// Σ over leaves of the previous rows' sizes, when the level had rows.
fn previous_sum(data: &[u8]) -> Option<usize> {
    let rows = vislump::read_rows(data).ok()?;
    rows.iter()
        .map(|r| {
            r.as_ref()
                .map(|r| r.iter().map(|b| b.count_ones() as usize).sum::<usize>())
        })
        .sum()
}

/// FNV-1a, 64 bits: a fixed, dependency-free hash for the state file's fingerprint
/// and checksums.
fn fnv(h: u64, bytes: &[u8]) -> u64 {
    bytes.iter().fold(h, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}
const FNV0: u64 = 0xcbf2_9ce4_8422_2325;

fn fingerprint(level: &[u8], prt: Option<&[u8]>, mode: Mode) -> u64 {
    let mut h = fnv(FNV0, b"sightline vis state 1 ");
    h = fnv(h, env!("CARGO_PKG_VERSION").as_bytes());
    h = fnv(h, &(level.len() as u64).to_le_bytes());
    h = fnv(h, level);
    match prt {
        Some(p) => {
            h = fnv(h, &(p.len() as u64).to_le_bytes());
            h = fnv(h, p);
        }
        None => h = fnv(h, b"tree"),
    }
    fnv(h, format!("{mode:?}").as_bytes())
}

const STATE_MAGIC: &[u8; 8] = b"SLVISST1";

/// The shape of the state: directed portals, 64-bit words per cell and portal set.
#[derive(Clone, Copy, PartialEq, Eq)]
struct Shape {
    portals: usize,
    cell_words: usize,
    portal_words: usize,
}

fn header(fingerprint: u64, s: Shape) -> Vec<u8> {
    let mut h = STATE_MAGIC.to_vec();
    h.extend_from_slice(&fingerprint.to_le_bytes());
    for v in [s.portals, s.cell_words, s.portal_words] {
        h.extend_from_slice(&(v as u64).to_le_bytes());
    }
    h
}

/// The flows already in the state file (complete, checksummed waves only); empty
/// when there is none or it belongs to other inputs.
fn load_state(path: &Path, fingerprint: u64, s: Shape) -> Vec<Option<Seen>> {
    let mut done = vec![None; s.portals];
    let Ok(bytes) = std::fs::read(path) else {
        return done;
    };
    let head = header(fingerprint, s);
    if !bytes.starts_with(&head) {
        return done;
    }
    let mut at = head.len();
    let u64_at = |o: usize| -> Option<u64> {
        Some(u64::from_le_bytes(bytes.get(o..o + 8)?.try_into().ok()?))
    };
    let per = 8 * (1 + s.cell_words + s.portal_words);
    // A record: count, then count × (portal, cells, portals), then its checksum.
    while let Some(count) = u64_at(at) {
        let count = count as usize;
        let Some(len) = count.checked_mul(per).filter(|&l| l <= bytes.len()) else {
            break;
        };
        let body = at + 8;
        let Some(sum) = u64_at(body + len) else { break };
        if fnv(FNV0, &bytes[at..body + len]) != sum {
            break;
        }
        for k in 0..count {
            let o = body + k * per;
            let words = |o: usize, n: usize| -> Vec<u64> {
                (0..n).filter_map(|i| u64_at(o + 8 * i)).collect()
            };
            let p = u64_at(o).unwrap_or(u64::MAX) as usize;
            if p >= s.portals {
                return vec![None; s.portals];
            }
            done[p] = Some(Seen {
                cells: Bits(words(o + 8, s.cell_words)),
                portals: Bits(words(o + 8 + 8 * s.cell_words, s.portal_words)),
            });
        }
        at = body + len + 8;
    }
    done
}

/// The full flow of every directed portal, resumed from and recorded in the state
/// file; also how many flows were taken from it.
fn full_flow(
    portals: &Portals,
    state: &Path,
    fingerprint: u64,
    stop_after: Option<usize>,
    quiet: bool,
) -> anyhow::Result<(Vec<Seen>, usize)> {
    let g = portals.graph();
    let mightsee = portals.portal_sets(Mode::Fast);
    let shape = Shape {
        portals: g.portals.len(),
        cell_words: g.leaf_portals.len().div_ceil(64),
        portal_words: g.portals.len().div_ceil(64),
    };
    let done = load_state(state, fingerprint, shape);
    // Count only what the solver will take: complete leading waves.
    let waves = flow::flow_waves(g, mightsee);
    let resumed: usize = waves
        .iter()
        .take_while(|w| w.iter().all(|&p| done[p].is_some()))
        .map(|w| w.len())
        .sum();
    let complete_waves = waves
        .iter()
        .take_while(|w| w.iter().all(|&p| done[p].is_some()))
        .count();

    // Rewrite the state with exactly the waves kept, then append as waves finish.
    let mut file = std::fs::File::create(state)
        .with_context(|| format!("cannot write the state file {}", state.display()))?;
    let mut head = header(fingerprint, shape);
    for w in &waves[..complete_waves] {
        let pairs: Vec<(usize, &Seen)> = w
            .iter()
            .filter_map(|&p| done[p].as_ref().map(|s| (p, s)))
            .collect();
        head.extend_from_slice(&record(&pairs));
    }
    file.write_all(&head)
        .with_context(|| format!("cannot write the state file {}", state.display()))?;

    let bar = progress(g.portals.len() as u64, quiet, "vis: portal flows");
    bar.set_position(resumed as u64);
    let mut computed = 0usize;
    let result = flow::flow_all_resumable(g, mightsee, None, done, |_, pairs| {
        file.write_all(&record(pairs))
            .and_then(|_| file.sync_data())
            .with_context(|| format!("cannot write the state file {}", state.display()))?;
        bar.inc(pairs.len() as u64);
        computed += 1;
        if stop_after.is_some_and(|k| computed >= k) {
            bail!(
                "stopped after {computed} waves as asked; the state is in {}",
                state.display()
            );
        }
        Ok(())
    });
    bar.finish_and_clear();
    Ok((result?, resumed))
}

/// One wave's record in the state file.
fn record(pairs: &[(usize, &Seen)]) -> Vec<u8> {
    let mut r = (pairs.len() as u64).to_le_bytes().to_vec();
    for (p, s) in pairs {
        r.extend_from_slice(&(*p as u64).to_le_bytes());
        for w in s.cells.0.iter().chain(&s.portals.0) {
            r.extend_from_slice(&w.to_le_bytes());
        }
    }
    let sum = fnv(FNV0, &r);
    r.extend_from_slice(&sum.to_le_bytes());
    r
}

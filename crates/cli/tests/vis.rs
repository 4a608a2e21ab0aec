//! `sightline vis LEVEL.bsp`: the written visibility lump read back as an engine reads
//! it (the `qbsp` crate, the reader of Bevy's Quake loaders), the other lumps byte for
//! byte, the ray oracle, thread-count independence, resume, and bad input.

mod common;

use common::sightline;
use sightline_portals::oracle::{pair_visible, sample_leaf, Rng};
use sightline_portals::vislump::{self, Lumps};
use sightline_portals::{flow, Portals};
use sightline_scene::import::bsp::read_bsp;
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/quake")
        .join(name)
}

/// A writable copy of a level in a fresh temporary folder.
fn copy_level(dir: &Path, name: &str) -> PathBuf {
    let to = dir.join(name);
    std::fs::write(&to, std::fs::read(data(name)).unwrap()).unwrap();
    to
}

fn s(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// The files of a folder, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Leaves of row `l` as the `qbsp` crate decodes it. Its iterator runs on past the row
/// into the following bytes up to the level's total leaf count (not `visleafs`), so only
/// leaves `1 ..= visleafs` are taken: exactly the row's bits, since a row covers leaves
/// `1 ..= 8 * ceil(visleafs / 8)` and its padding bits are zero.
fn qbsp_row(bsp: &qbsp::BspData, leaf: usize, visleafs: usize) -> Vec<u32> {
    let Some(set) = bsp.potentially_visible_set(leaf) else {
        panic!("leaf {leaf} has no visdata in qbsp's reading");
    };
    let Ok(iter) = set.into_leaf_indices() else {
        panic!("leaf {leaf}: qbsp answers clusters, not leaves");
    };
    iter.filter(|&j| j <= visleafs).map(|j| j as u32).collect()
}

#[test]
fn vis_on_dm1_reads_back_as_an_engine_reads_it() {
    let dir = tempfile::tempdir().unwrap();
    let prt = data("dm1.prt");
    let mut outputs = Vec::new();
    for threads in ["1", "2", "8"] {
        let sub = dir.path().join(format!("t{threads}"));
        std::fs::create_dir(&sub).unwrap();
        let level = copy_level(&sub, "dm1.bsp");
        let (code, out, err) = sightline(&[
            "vis",
            &s(&level),
            "--prt",
            &s(&prt),
            "--threads",
            threads,
            "--quiet",
        ]);
        assert_eq!(code, 0, "{err}");
        assert!(out.contains("434 visleafs"), "{out}");
        assert_eq!(
            listing(&sub),
            ["dm1.bsp", "dm1.bsp.orig"],
            "no state or temp file left"
        );
        outputs.push(std::fs::read(&level).unwrap());
    }
    assert!(outputs[0] == outputs[1], "1 and 2 threads differ");
    assert!(outputs[0] == outputs[2], "1 and 8 threads differ");
    let original = std::fs::read(data("dm1.bsp")).unwrap();
    assert!(std::fs::read(dir.path().join("t1/dm1.bsp.orig")).unwrap() == original);
    let written = &outputs[0];

    // Our rows, from the solver directly.
    let level = read_bsp(&original).unwrap();
    let file = sightline_portals::prt::parse_prt(&std::fs::read(&prt).unwrap()).unwrap();
    let portals = Portals::from_prt(&level, &file).unwrap();
    let flows = flow::flow_all(
        portals.graph(),
        portals.portal_sets(sightline_portals::Mode::Fast),
    );
    let ours: Vec<Vec<u32>> = portals
        .visleaf_sets(&flows)
        .iter()
        .map(|b| b.ones().map(|l| l as u32).collect())
        .collect();
    let visleafs = level.visleafs as usize;
    assert_eq!(ours.len(), visleafs);

    // Read as engines read it: the qbsp crate, and our importer's own decoder.
    let bsp = qbsp::BspData::parse(qbsp::BspParseInput {
        bsp: written,
        lit: None,
        settings: qbsp::BspParseSettings::default(),
    })
    .unwrap();
    let reread = read_bsp(written).unwrap();
    for l in 1..=visleafs {
        assert_eq!(qbsp_row(&bsp, l, visleafs), ours[l - 1], "leaf {l} (qbsp)");
        assert_eq!(
            reread.reference_row(l as u32),
            ours[l - 1],
            "leaf {l} (importer)"
        );
    }

    // Every lump but the visibility one byte-identical; leaves differ only in visofs.
    let (a, b) = (
        Lumps::read(&original).unwrap(),
        Lumps::read(written).unwrap(),
    );
    for i in 0..15 {
        let (la, lb) = (a.lump(&original, i), b.lump(written, i));
        match i {
            4 => {}
            10 => {
                assert_eq!(la.len(), lb.len());
                for (k, (ra, rb)) in la.chunks(28).zip(lb.chunks(28)).enumerate() {
                    assert_eq!(ra[..4], rb[..4], "leaf {k}");
                    assert_eq!(ra[8..], rb[8..], "leaf {k}");
                    if k == 0 || k > visleafs {
                        assert_eq!(ra[4..8], rb[4..8], "leaf {k}'s visofs moved");
                    }
                }
            }
            _ => assert!(la == lb, "lump {i} changed"),
        }
        assert_eq!(b.lumps[i].0 % 4, 0, "lump {i} unaligned");
    }
    // Lump order kept.
    let order = |d: &Lumps| {
        let mut o: Vec<usize> = (0..15).filter(|&i| d.lumps[i].1 > 0).collect();
        o.sort_by_key(|&i| d.lumps[i].0);
        o
    };
    assert_eq!(order(&a), order(&b));

    // The level still loads with the same faces and tree.
    assert_eq!(reread.faces, level.faces);
    assert_eq!(reread.nodes, level.nodes);
    assert_eq!(reread.planes, level.planes);

    // Ray oracle: no clear segment from a sampled leaf to a leaf its row lacks.
    let mut rng = Rng::new(49);
    let view: Vec<u32> = (1..=level.visleafs)
        .filter(|&l| level.is_view_leaf(l))
        .collect();
    let points: Vec<Vec<[f64; 3]>> = (0..level.leaves.len() as u32)
        .map(|l| sample_leaf(&level, l, 12, &mut rng))
        .collect();
    let mut misses = Vec::new();
    for &src in view.iter().step_by(view.len() / 40) {
        let row = &ours[src as usize - 1];
        for &t in &view {
            if row.binary_search(&t).is_err()
                && pair_visible(
                    &level,
                    &points[src as usize],
                    &points[t as usize],
                    16,
                    &mut rng,
                )
            {
                misses.push((src, t));
            }
        }
    }
    assert!(misses.is_empty(), "missed pairs: {misses:?}");
}

#[test]
fn an_interrupted_run_resumes_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let prt = s(&data("dm1.prt"));
    let whole = copy_level(dir.path(), "dm1.bsp");
    let (code, _, err) = sightline(&["vis", &s(&whole), "--prt", &prt, "--in-place", "--quiet"]);
    assert_eq!(code, 0, "{err}");

    let sub = dir.path().join("second");
    std::fs::create_dir(&sub).unwrap();
    let level = copy_level(&sub, "dm1.bsp");
    let args = [
        "vis",
        &s(&level),
        "--prt",
        &prt,
        "--quiet",
        "--threads",
        "2",
    ];
    let mut stopped = args.to_vec();
    stopped.extend(["--stop-after-waves", "3"]);
    let (code, _, err) = sightline(&stopped);
    assert_ne!(code, 0);
    assert!(
        err.starts_with("error:") && err.trim().lines().count() == 1,
        "{err}"
    );
    assert!(std::fs::read(&level).unwrap() == std::fs::read(data("dm1.bsp")).unwrap());
    assert_eq!(listing(&sub), ["dm1.bsp", "dm1.vis-state"]);

    let (code, out, err) = sightline(&args);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("portal flows resumed"), "{out}");
    assert!(std::fs::read(&level).unwrap() == std::fs::read(&whole).unwrap());
    assert_eq!(listing(&sub), ["dm1.bsp", "dm1.bsp.orig"]);

    // A state file of other inputs is ignored, never trusted.
    std::fs::write(sub.join("dm1.vis-state"), b"SLVISST1 not this level").unwrap();
    let again = copy_level(&sub, "dm1.bsp");
    let (code, out, err) = sightline(&["vis", &s(&again), "--prt", &prt, "--in-place", "--quiet"]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("flows resumed"), "{out}");
    assert!(std::fs::read(&again).unwrap() == std::fs::read(&whole).unwrap());
}

/// A bad input: one `error:` line naming `want`, a non-zero exit, the level untouched
/// and nothing else left in its folder.
fn refused(level_bytes: &[u8], prt: Option<&[u8]>, extra: &[&str], want: &str) {
    let dir = tempfile::tempdir().unwrap();
    let level = dir.path().join("level.bsp");
    std::fs::write(&level, level_bytes).unwrap();
    let mut args = vec!["vis".to_string(), s(&level), "--fast".into()];
    if let Some(p) = prt {
        let path = dir.path().join("level.prt");
        std::fs::write(&path, p).unwrap();
        args.extend(["--prt".into(), s(&path)]);
    }
    args.extend(extra.iter().map(|a| a.to_string()));
    let before = listing(dir.path());
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, _, err) = sightline(&refs);
    assert_ne!(code, 0, "{want}: accepted");
    assert!(err.starts_with("error:"), "{want}: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains(want), "expected '{want}' in {err}");
    assert!(
        std::fs::read(&level).unwrap() == level_bytes,
        "{want}: level changed"
    );
    assert_eq!(listing(dir.path()), before, "{want}: files left behind");
}

fn set_i32(v: &mut [u8], at: usize, x: i32) {
    v[at..at + 4].copy_from_slice(&x.to_le_bytes());
}

#[test]
fn bad_levels_are_refused_and_left_untouched() {
    let dm1 = std::fs::read(data("dm1.bsp")).unwrap();
    refused(&dm1[..1000], None, &[], "outside the file");
    refused(&dm1[..10], None, &[], "truncated lump directory");
    refused(&[], None, &[], "too short");
    refused(b"IBSP\x26\0\0\0", None, &[], "not a Quake BSP");
    let mut hostile = dm1.clone();
    set_i32(&mut hostile, 4 + 8 * 10, i32::MAX - 4); // leaves lump offset
    refused(&hostile, None, &[], "outside the file");
    let mut odd = dm1.clone();
    set_i32(&mut odd, 8 + 8 * 10, 28 * 10 + 3); // leaves lump length
    refused(&odd, None, &[], "not a multiple");
    let mut nodes = dm1.clone();
    let node_lump = i32::from_le_bytes(dm1[4 + 8 * 5..8 + 8 * 5].try_into().unwrap()) as usize;
    set_i32(&mut nodes, node_lump, 1 << 30); // node 0's plane
    refused(&nodes, None, &[], "missing plane");
    let mut bsp2 = dm1.clone();
    bsp2[..4].copy_from_slice(b"BSP2"); // BSP29 records under a BSP2 header
    refused(&bsp2, None, &[], "not a multiple of 44");
    refused(&dm1, None, &["--threads", "0"], "--threads");

    // Over the format's limit: 32,769 leaf records in a BSP29 file.
    let n = 32_769usize;
    let mut big = vec![0u8; 4 + 8 * 15];
    set_i32(&mut big, 0, 29);
    let leaves_at = big.len();
    big.resize(leaves_at + 28 * n, 0);
    let models_at = big.len();
    big.resize(models_at + 64, 0);
    set_i32(&mut big, models_at + 52, 100); // visleafs
    set_i32(&mut big, 4 + 8 * 10, leaves_at as i32);
    set_i32(&mut big, 8 + 8 * 10, (28 * n) as i32);
    set_i32(&mut big, 4 + 8 * 14, models_at as i32);
    set_i32(&mut big, 8 + 8 * 14, 64);
    let end = big.len() as i32;
    for i in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13] {
        set_i32(&mut big, 4 + 8 * i, end);
    }
    refused(&big, None, &[], "exceed BSP29's limit of 32768");
}

#[test]
fn bad_portal_files_are_refused_and_leave_the_level_untouched() {
    let dm1 = std::fs::read(data("dm1.bsp")).unwrap();
    let prt = std::fs::read_to_string(data("dm1.prt")).unwrap();
    refused(
        &dm1,
        Some(&prt.as_bytes()[..prt.len() / 2]),
        &[],
        "PRT: line",
    );
    refused(&dm1, Some(b"\x00\xff\xfe garbage"), &[], "PRT: line 1");
    refused(
        &dm1,
        Some(b"PRT2\n1\n1\n0\n"),
        &[],
        "PRT2 files are not supported",
    );
    let more = prt.replacen("434\n", "435\n", 1);
    refused(
        &dm1,
        Some(more.as_bytes()),
        &[],
        "435 leaves, the level has 434",
    );
    // A portal moved 500 units away: it lies outside its leaves.
    let lines: Vec<&str> = prt.lines().collect();
    let moved: Vec<String> = lines
        .iter()
        .enumerate()
        .map(|(i, l)| {
            if i == 3 {
                l.replace("(544 ", "(1044 ")
            } else {
                l.to_string()
            }
        })
        .collect();
    refused(
        &dm1,
        Some(moved.join("\n").as_bytes()),
        &[],
        "outside the box of leaf",
    );
    // A leaf out of the file's range.
    let far = prt.replacen("\n5 17 75 ", "\n5 17 999 ", 1);
    refused(&dm1, Some(far.as_bytes()), &[], "out of range");
    // The other level's portals (e1m1's leaf count differs from dm1's).
    let e1m1 = std::fs::read(data("e1m1.bsp")).unwrap();
    refused(&e1m1, Some(prt.as_bytes()), &[], "does not match the level");
}

#[test]
fn the_lump_writer_round_trips_any_rows() {
    let dm1 = std::fs::read(data("dm1.bsp")).unwrap();
    let visleafs = 434;
    let mut rng = Rng::new(7);
    let rows: Vec<Vec<u8>> = (0..visleafs)
        .map(|k| {
            let density = [0.0, 0.01, 0.5, 1.0][k % 4];
            let leaves = (1..=visleafs as u32).filter(|_| rng.unit() < density);
            vislump::row_of(leaves, visleafs)
        })
        .collect();
    let out = vislump::write_vis(&dm1, &rows).unwrap();
    let back = vislump::read_rows(&out).unwrap();
    assert!(back.iter().zip(&rows).all(|(b, r)| b.as_ref() == Some(r)));
    // Writing the same rows again changes nothing.
    assert!(vislump::write_vis(&out, &rows).unwrap() == out);
    assert!(vislump::write_vis(&dm1, &rows[1..]).is_err());
}

/// dm1 converted to a 32-bit format (`BSP2`: float bounds; `2PSB`: short bounds): the
/// nodes, faces, clipnodes, leaves, marksurfaces and edges widened, other lumps copied.
fn widen(bsp29: &[u8], magic: &[u8; 4]) -> Vec<u8> {
    let dir = Lumps::read(bsp29).unwrap();
    let float = magic == b"BSP2";
    let i16s = |r: &[u8], o: usize| i16::from_le_bytes([r[o], r[o + 1]]);
    let u16s = |r: &[u8], o: usize| u16::from_le_bytes([r[o], r[o + 1]]);
    let bounds = |out: &mut Vec<u8>, r: &[u8], o: usize| {
        for k in 0..6 {
            let v = i16s(r, o + 2 * k);
            if float {
                out.extend_from_slice(&(v as f32).to_le_bytes());
            } else {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    };
    let mut out = vec![0u8; 4 + 8 * 15];
    out[..4].copy_from_slice(magic);
    for i in 0..15 {
        let l = dir.lump(bsp29, i);
        let mut w = Vec::new();
        match i {
            5 => {
                for r in l.chunks(24) {
                    w.extend_from_slice(&r[..4]);
                    w.extend_from_slice(&(i16s(r, 4) as i32).to_le_bytes());
                    w.extend_from_slice(&(i16s(r, 6) as i32).to_le_bytes());
                    bounds(&mut w, r, 8);
                    w.extend_from_slice(&(u16s(r, 20) as u32).to_le_bytes());
                    w.extend_from_slice(&(u16s(r, 22) as u32).to_le_bytes());
                }
            }
            7 => {
                for r in l.chunks(20) {
                    w.extend_from_slice(&(u16s(r, 0) as i32).to_le_bytes());
                    w.extend_from_slice(&(i16s(r, 2) as i32).to_le_bytes());
                    w.extend_from_slice(&r[4..8]);
                    w.extend_from_slice(&(i16s(r, 8) as i32).to_le_bytes());
                    w.extend_from_slice(&(i16s(r, 10) as i32).to_le_bytes());
                    w.extend_from_slice(&r[12..20]);
                }
            }
            9 => {
                for r in l.chunks(8) {
                    w.extend_from_slice(&r[..4]);
                    w.extend_from_slice(&(i16s(r, 4) as i32).to_le_bytes());
                    w.extend_from_slice(&(i16s(r, 6) as i32).to_le_bytes());
                }
            }
            10 => {
                for r in l.chunks(28) {
                    w.extend_from_slice(&r[..8]);
                    bounds(&mut w, r, 8);
                    w.extend_from_slice(&(u16s(r, 20) as u32).to_le_bytes());
                    w.extend_from_slice(&(u16s(r, 22) as u32).to_le_bytes());
                    w.extend_from_slice(&r[24..28]);
                }
            }
            11 | 12 => {
                for r in l.chunks(2) {
                    w.extend_from_slice(&(u16s(r, 0) as u32).to_le_bytes());
                }
            }
            _ => w.extend_from_slice(l),
        }
        let at = out.len();
        out[4 + 8 * i..8 + 8 * i].copy_from_slice(&(at as i32).to_le_bytes());
        out[8 + 8 * i..12 + 8 * i].copy_from_slice(&(w.len() as i32).to_le_bytes());
        out.extend_from_slice(&w);
        out.resize(out.len().next_multiple_of(4), 0);
    }
    out
}

#[test]
fn bsp2_and_2psb_levels_get_the_same_rows() {
    let dir = tempfile::tempdir().unwrap();
    let dm1 = std::fs::read(data("dm1.bsp")).unwrap();
    let base = read_bsp(&dm1).unwrap();
    let narrow = copy_level(dir.path(), "dm1.bsp");
    let (code, _, err) = sightline(&["vis", &s(&narrow), "--fast", "--in-place", "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let want = vislump::read_rows(&std::fs::read(&narrow).unwrap()).unwrap();
    for magic in [b"BSP2", b"2PSB"] {
        let wide = widen(&dm1, magic);
        let level = read_bsp(&wide).unwrap();
        assert_eq!(level.faces, base.faces);
        assert_eq!(level.nodes, base.nodes);
        assert_eq!(level.leaves, base.leaves);
        let path = dir
            .path()
            .join(format!("{}.bsp", String::from_utf8_lossy(magic)));
        std::fs::write(&path, &wide).unwrap();
        let (code, _, err) = sightline(&["vis", &s(&path), "--fast", "--quiet"]);
        assert_eq!(code, 0, "{err}");
        let written = std::fs::read(&path).unwrap();
        assert_eq!(vislump::read_rows(&written).unwrap(), want);
        let (a, b) = (Lumps::read(&wide).unwrap(), Lumps::read(&written).unwrap());
        for i in (0..15).filter(|&i| i != 4 && i != 10) {
            assert!(a.lump(&wide, i) == b.lump(&written, i), "lump {i} changed");
        }
        if magic == b"BSP2" {
            let bsp = qbsp::BspData::parse(qbsp::BspParseInput {
                bsp: &written,
                lit: None,
                settings: qbsp::BspParseSettings::default(),
            })
            .unwrap();
            for l in 1..=434 {
                let row = want[l - 1].as_ref().unwrap();
                let leaves: Vec<u32> = (0..434u32)
                    .filter(|j| row[*j as usize >> 3] & (1 << (j & 7)) != 0)
                    .map(|j| j + 1)
                    .collect();
                assert_eq!(qbsp_row(&bsp, l, 434), leaves, "BSP2 leaf {l}");
            }
        }
    }
}

/// A BSPX block after the last lump moves with the lumps, its offsets shifted; unknown
/// trailing data is refused.
#[test]
fn a_bspx_block_moves_with_the_lumps() {
    let mut dm1 = std::fs::read(data("dm1.bsp")).unwrap();
    dm1.resize(dm1.len().next_multiple_of(4), 0);
    let at = dm1.len();
    let payload = b"RGB lighting, say";
    let mut bspx = b"BSPX".to_vec();
    bspx.extend_from_slice(&1u32.to_le_bytes());
    let mut name = [0u8; 24];
    name[..11].copy_from_slice(b"RGBLIGHTING");
    bspx.extend_from_slice(&name);
    bspx.extend_from_slice(&((at + 40) as u32).to_le_bytes());
    bspx.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    bspx.extend_from_slice(payload);
    dm1.extend_from_slice(&bspx);
    let rows = vec![vislump::row_of([1, 2, 3], 434); 434];
    let out = vislump::write_vis(&dm1, &rows).unwrap();
    let start = out.windows(4).rposition(|w| w == b"BSPX").unwrap();
    let ofs = u32::from_le_bytes(out[start + 32..start + 36].try_into().unwrap()) as usize;
    assert_eq!(ofs, start + 40);
    assert_eq!(&out[ofs..ofs + payload.len()], payload);
    assert_eq!(out.len() - start, bspx.len());
    let mut junk = std::fs::read(data("dm1.bsp")).unwrap();
    junk.extend_from_slice(b"????????");
    let e = vislump::write_vis(&junk, &rows).unwrap_err().to_string();
    assert!(e.contains("unknown data"), "{e}");
}

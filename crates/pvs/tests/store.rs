//! The store end to end: encode/decode, build determinism, resume after interruption,
//! torn and damaged journals, truncated and bit-flipped files, shards and merge.

mod common;

use common::{grid_cells, grid_scene, nearby, Nearby};
use proptest::prelude::*;
use roaring::RoaringBitmap;
use sightline_geom::{DVec3, ViewCell};
use sightline_methods::{MethodError, VisibilityMethod};
use sightline_pvs::build::journal_path;
use sightline_pvs::format::{encode, encode_with, EncodeOptions, Header};
use sightline_pvs::{build, merge, BuildOptions, PvsError, PvsFile, Shard};
use sightline_scene::Scene;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

fn fixture() -> (Arc<Scene>, Vec<ViewCell>) {
    (Arc::new(grid_scene(20)), grid_cells(10, 10, 20.0))
}

fn no_progress(_: usize, _: usize) {}

fn build_into(
    dir: &Path,
    name: &str,
    scene: &Scene,
    m: &dyn VisibilityMethod,
    cells: &[ViewCell],
    opts: &BuildOptions,
) -> Vec<u8> {
    let out = dir.join(name);
    build(scene, m, cells, &out, opts, &no_progress).unwrap();
    std::fs::read(out).unwrap()
}

#[test]
fn every_cell_decodes_to_its_set_and_points_find_their_cell() {
    let (scene, cells) = fixture();
    let m = nearby(&scene);
    let sets: Vec<Vec<u32>> = cells.iter().map(|c| m.pvs(c).unwrap()).collect();
    let header = Header::new(
        scene.fingerprint(),
        "nearby",
        m.params(),
        scene.objects.len(),
        cells.len(),
    );
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    let bytes = encode(&header, &cells, &present, &sets).unwrap();
    let file = PvsFile::from_bytes(bytes).unwrap();
    assert_eq!(file.header(), &header);
    for (i, c) in cells.iter().enumerate() {
        assert_eq!(file.pvs(i).unwrap(), sets[i]);
        let (cell, visible) = file.query(c.center()).unwrap().unwrap();
        assert_eq!((cell, &visible), (*c, &sets[i]));
    }
    assert!(file.query(DVec3::new(-1.0, 1.0, 1.7)).unwrap().is_none());
    let all: Vec<_> = file.iter().collect::<Result<_, _>>().unwrap();
    assert_eq!(all.len(), cells.len());
    file.verify().unwrap();
    file.check_scene(&scene).unwrap();
}

#[test]
fn delta_pvs_is_smaller_than_whole_sets() {
    let (scene, cells) = fixture();
    let m = Nearby {
        scene: scene.clone(),
        radius: 80.0,
    };
    let sets: Vec<RoaringBitmap> = cells
        .iter()
        .map(|c| m.pvs(c).unwrap().into_iter().collect())
        .collect();
    let header = Header::new(1, "nearby", vec![], scene.objects.len(), cells.len());
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    let delta = encode_with(
        &header,
        &cells,
        &present,
        &sets,
        &EncodeOptions { delta: true },
    )
    .unwrap();
    let whole = encode_with(
        &header,
        &cells,
        &present,
        &sets,
        &EncodeOptions { delta: false },
    )
    .unwrap();
    assert!(
        delta.len() <= whole.len(),
        "delta {} vs whole {}",
        delta.len(),
        whole.len()
    );
    let f = PvsFile::from_bytes(whole).unwrap();
    assert_eq!(f.bitmap(17).unwrap(), sets[17]);

    // Large sets that change a little from cell to cell (a street walked along): the
    // differences are far smaller than the sets.
    let sets: Vec<RoaringBitmap> = (0..cells.len() as u64)
        .map(|k| {
            let (i, j) = (k % 10, k / 10);
            (0..60_000u64)
                .filter(|&id| {
                    let h = id.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
                    h % 7 < 3 && (h % 1000 >= i * 3 + j) && (h % 1000 < 900 + i * 3 + j)
                })
                .map(|id| id as u32)
                .collect()
        })
        .collect();
    let header = Header::new(1, "nearby", vec![], 60_000, cells.len());
    let delta = encode_with(
        &header,
        &cells,
        &present,
        &sets,
        &EncodeOptions { delta: true },
    )
    .unwrap();
    let whole = encode_with(
        &header,
        &cells,
        &present,
        &sets,
        &EncodeOptions { delta: false },
    )
    .unwrap();
    // zstd over a 512 KiB block already finds much of the overlap of whole sets, so
    // the margin is modest (13.2 kB against 15.2 kB), but the delta must still win.
    assert!(
        delta.len() < whole.len(),
        "delta {} vs whole {}",
        delta.len(),
        whole.len()
    );
    let f = PvsFile::from_bytes(delta).unwrap();
    for k in [0, 17, 99] {
        assert_eq!(f.bitmap(k).unwrap(), sets[k]);
    }
}

#[test]
fn build_output_does_not_depend_on_threads() {
    let (scene, cells) = fixture();
    let m = nearby(&scene);
    let dir = tempfile::tempdir().unwrap();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let a = one.install(|| {
        build_into(
            dir.path(),
            "a.pvs",
            &scene,
            &m,
            &cells,
            &BuildOptions::default(),
        )
    });
    let b = three.install(|| {
        build_into(
            dir.path(),
            "b.pvs",
            &scene,
            &m,
            &cells,
            &BuildOptions::default(),
        )
    });
    assert_eq!(a, b);
    assert!(
        !journal_path(&dir.path().join("a.pvs")).exists(),
        "journal removed after success"
    );
}

/// Fails on every cell after the first `ok` (as if killed), reporting the same name and
/// parameters as the method it wraps.
struct FailAfter {
    inner: Nearby,
    ok: usize,
    seen: AtomicUsize,
}

impl VisibilityMethod for FailAfter {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn params(&self) -> Vec<(String, String)> {
        self.inner.params()
    }
    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        if self.seen.fetch_add(1, Ordering::SeqCst) >= self.ok {
            return Err(MethodError::Other("interrupted".into()));
        }
        self.inner.pvs(cell)
    }
}

fn interrupted_build(
    dir: &Path,
    scene: &Arc<Scene>,
    cells: &[ViewCell],
    ok: usize,
) -> std::path::PathBuf {
    let out = dir.join("r.pvs");
    let failing = FailAfter {
        inner: nearby(scene),
        ok,
        seen: AtomicUsize::new(0),
    };
    let err = build(
        scene,
        &failing,
        cells,
        &out,
        &BuildOptions::default(),
        &no_progress,
    )
    .unwrap_err();
    assert!(matches!(err, PvsError::Method { .. }), "{err}");
    assert!(!out.exists());
    out
}

#[test]
fn resume_after_interruption_and_torn_record_is_byte_identical() {
    let (scene, cells) = fixture();
    let m = nearby(&scene);
    let dir = tempfile::tempdir().unwrap();
    let whole = build_into(
        dir.path(),
        "whole.pvs",
        &scene,
        &m,
        &cells,
        &BuildOptions::default(),
    );

    let out = interrupted_build(dir.path(), &scene, &cells, 37);
    let journal = journal_path(&out);
    // Without --resume an existing journal is refused, not overwritten.
    let err = build(
        &scene,
        &m,
        &cells,
        &out,
        &BuildOptions::default(),
        &no_progress,
    )
    .unwrap_err();
    assert!(err.to_string().contains("--resume"), "{err}");
    // A torn last record: the first half of a copy of the first record appended.
    let mut bytes = std::fs::read(&journal).unwrap();
    let key_len = u32::from_le_bytes(bytes[10..14].try_into().unwrap()) as usize;
    let first = 14 + key_len + 4;
    let len = u32::from_le_bytes(bytes[first..first + 4].try_into().unwrap()) as usize;
    let torn = bytes[first..first + (12 + len) / 2 + 6].to_vec();
    bytes.extend_from_slice(&torn);
    std::fs::write(&journal, &bytes).unwrap();

    let counted = AtomicUsize::new(0);
    let start = std::sync::Mutex::new(None);
    let progress = |done: usize, total: usize| {
        counted.fetch_add(1, Ordering::SeqCst);
        start.lock().unwrap().get_or_insert((done, total));
    };
    let opts = BuildOptions {
        resume: true,
        ..BuildOptions::default()
    };
    let stats = build(&scene, &m, &cells, &out, &opts, &progress).unwrap();
    assert_eq!(stats.resumed, 37);
    assert_eq!(stats.computed, cells.len() - 37);
    assert_eq!(*start.lock().unwrap(), Some((37, cells.len())));
    assert_eq!(std::fs::read(&out).unwrap(), whole);
    assert!(!journal.exists());
}

#[test]
fn damaged_or_foreign_journals_are_clear_errors() {
    let (scene, cells) = fixture();
    let m = nearby(&scene);
    let dir = tempfile::tempdir().unwrap();
    let out = interrupted_build(dir.path(), &scene, &cells, 30);
    let journal = journal_path(&out);
    let good = std::fs::read(&journal).unwrap();
    let resume = BuildOptions {
        resume: true,
        ..BuildOptions::default()
    };

    // A bit flip in a record that is not the last one.
    let mut bad = good.clone();
    let mid = good.len() / 2;
    bad[mid] ^= 0x10;
    std::fs::write(&journal, &bad).unwrap();
    let err = build(&scene, &m, &cells, &out, &resume, &no_progress).unwrap_err();
    assert!(matches!(err, PvsError::Journal { .. }), "{err}");
    assert!(err.to_string().contains("checksum"), "{err}");

    // A bit flip in the header.
    let mut bad = good.clone();
    bad[20] ^= 1;
    std::fs::write(&journal, &bad).unwrap();
    let err = build(&scene, &m, &cells, &out, &resume, &no_progress).unwrap_err();
    assert!(matches!(err, PvsError::Journal { .. }), "{err}");

    // Not a journal at all.
    std::fs::write(&journal, b"hello").unwrap();
    let err = build(&scene, &m, &cells, &out, &resume, &no_progress).unwrap_err();
    assert!(
        err.to_string().contains("not a sightline build journal"),
        "{err}"
    );

    // The journal of another build (other parameters).
    std::fs::write(&journal, &good).unwrap();
    let other = Nearby {
        scene: scene.clone(),
        radius: 30.0,
    };
    let err = build(&scene, &other, &cells, &out, &resume, &no_progress).unwrap_err();
    assert!(err.to_string().contains("another build"), "{err}");
    assert!(!out.exists());
}

fn small_file() -> (Vec<u8>, Arc<Scene>) {
    let scene = Arc::new(grid_scene(12));
    let cells = grid_cells(6, 6, 20.0);
    let m = nearby(&scene);
    let sets: Vec<Vec<u32>> = cells.iter().map(|c| m.pvs(c).unwrap()).collect();
    let header = Header::new(
        scene.fingerprint(),
        "nearby",
        m.params(),
        scene.objects.len(),
        cells.len(),
    );
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    (encode(&header, &cells, &present, &sets).unwrap(), scene)
}

#[test]
fn truncated_files_are_clear_errors() {
    let (bytes, _) = small_file();
    for cut in (0..bytes.len()).step_by(7).chain([bytes.len() - 1]) {
        let err = PvsFile::from_bytes(bytes[..cut].to_vec()).unwrap_err();
        assert!(
            matches!(err, PvsError::Truncated(_) | PvsError::NotPvs),
            "cut at {cut}: {err}"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("cut.pvs");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    let err = PvsFile::open(&p).unwrap_err();
    assert!(err.to_string().starts_with("truncated .pvs file"), "{err}");
}

#[test]
fn every_bit_flip_is_detected() {
    let (bytes, _) = small_file();
    let original = PvsFile::from_bytes(bytes.clone()).unwrap();
    let expected: Vec<_> = original.iter().collect::<Result<_, _>>().unwrap();
    for pos in 0..bytes.len() {
        let mut b = bytes.clone();
        b[pos] ^= 1 << (pos % 8);
        let detected = match PvsFile::from_bytes(b) {
            Err(_) => true,
            Ok(f) => f.verify().is_err(),
        };
        assert!(
            detected,
            "flip at byte {pos} of {} not detected",
            bytes.len()
        );
    }
    assert_eq!(expected.len(), 36);
}

#[test]
fn a_pvs_used_with_another_scene_is_an_error() {
    let (bytes, scene) = small_file();
    let f = PvsFile::from_bytes(bytes).unwrap();
    f.check_scene(&scene).unwrap();
    let err = f.check_scene(&grid_scene(11)).unwrap_err();
    assert!(matches!(err, PvsError::SceneMismatch { .. }));
    assert!(err.to_string().contains("another scene"), "{err}");
}

#[test]
fn shards_merge_into_the_whole_build() {
    let (scene, cells) = fixture();
    let m = nearby(&scene);
    let dir = tempfile::tempdir().unwrap();
    let whole = build_into(
        dir.path(),
        "whole.pvs",
        &scene,
        &m,
        &cells,
        &BuildOptions::default(),
    );
    let shard_file = |i: u32, n: u32| {
        let opts = BuildOptions {
            shard: Some(Shard { index: i, count: n }),
            ..BuildOptions::default()
        };
        let name = format!("s{i}of{n}.pvs");
        build_into(dir.path(), &name, &scene, &m, &cells, &opts);
        (name.clone(), PvsFile::open(dir.path().join(&name)).unwrap())
    };
    let shards: Vec<_> = (0..3).map(|i| shard_file(i, 3)).collect();
    assert_eq!(shards[1].1.stored().len(), 33);
    assert_eq!(shards[1].1.pvs(4).unwrap(), m.pvs(&cells[4]).unwrap());
    // Input order does not matter.
    let reversed: Vec<_> = shards
        .iter()
        .rev()
        .map(|(n, _)| (n.clone(), PvsFile::open(dir.path().join(n)).unwrap()))
        .collect();
    assert_eq!(merge(&shards).unwrap(), whole);
    assert_eq!(merge(&reversed).unwrap(), whole);

    // A missing shard, a shard given twice, a shard of another method.
    let err = merge(&shards[..2]).unwrap_err();
    assert!(err.to_string().contains("in no input"), "{err}");
    let twice = vec![
        (
            shards[0].0.clone(),
            PvsFile::open(dir.path().join(&shards[0].0)).unwrap(),
        ),
        (
            shards[0].0.clone(),
            PvsFile::open(dir.path().join(&shards[0].0)).unwrap(),
        ),
    ];
    assert!(merge(&twice).unwrap_err().to_string().contains("in both"));
    let other = Nearby {
        scene: scene.clone(),
        radius: 30.0,
    };
    let opts = BuildOptions {
        shard: Some(Shard { index: 2, count: 3 }),
        ..BuildOptions::default()
    };
    build_into(dir.path(), "other.pvs", &scene, &other, &cells, &opts);
    let mixed = vec![
        (
            shards[0].0.clone(),
            PvsFile::open(dir.path().join(&shards[0].0)).unwrap(),
        ),
        (
            shards[1].0.clone(),
            PvsFile::open(dir.path().join(&shards[1].0)).unwrap(),
        ),
        (
            "other.pvs".to_string(),
            PvsFile::open(dir.path().join("other.pvs")).unwrap(),
        ),
    ];
    assert!(merge(&mixed)
        .unwrap_err()
        .to_string()
        .contains("parameters"));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]
    #[test]
    fn random_sets_round_trip(
        sets in prop::collection::vec(prop::collection::btree_set(0u32..5000, 0..300), 1..40),
        width in 1usize..8,
    ) {
        let n = sets.len();
        let cells: Vec<ViewCell> = (0..n)
            .map(|k| {
                let (i, j) = ((k % width) as f64, (k / width) as f64);
                ViewCell::from_array([i * 5.0, j * 5.0, 0.0, i * 5.0 + 5.0, j * 5.0 + 5.0, 2.0]).unwrap()
            })
            .collect();
        let sets: Vec<Vec<u32>> = sets.into_iter().map(|s| s.into_iter().collect()).collect();
        let header = Header::new(7, "x", vec![], 5000, n);
        let present: Vec<u32> = (0..n as u32).collect();
        let f = PvsFile::from_bytes(encode(&header, &cells, &present, &sets).unwrap()).unwrap();
        for (i, s) in sets.iter().enumerate() {
            prop_assert_eq!(&f.pvs(i).unwrap(), s);
        }
    }
}

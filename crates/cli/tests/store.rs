//! `sightline build / merge / query` as a user runs them: a build killed with SIGKILL at
//! random moments and resumed gives the bytes of an uninterrupted build; shards merge
//! into the same bytes; damaged files give a one-line error.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Instant;

const BIN: &str = env!("CARGO_BIN_EXE_sightline");

/// A GeoJSON city of `side × side` blocks and a cells.json of `nx × ny` cells.
fn fixture(dir: &Path, side: usize, nx: usize, ny: usize) -> (PathBuf, PathBuf) {
    let mut features = Vec::new();
    for j in 0..side {
        for i in 0..side {
            let (x, y) = (i as f64 * 20.0, j as f64 * 20.0);
            let h = 6 + (i * 7 + j * 3) % 20;
            features.push(format!(
                r#"{{"type":"Feature","properties":{{"height":{h}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]]}}}}"#,
                x + 12.0,
                x + 12.0,
                y + 12.0,
                y + 12.0
            ));
        }
    }
    let scene = dir.join("city.geojson");
    std::fs::write(
        &scene,
        format!(
            r#"{{"type":"FeatureCollection","features":[{}]}}"#,
            features.join(",")
        ),
    )
    .unwrap();
    let size = side as f64 * 20.0 / nx.max(ny) as f64;
    let cells: Vec<String> = (0..ny)
        .flat_map(|j| (0..nx).map(move |i| (i, j)))
        .map(|(i, j)| {
            format!(
                "[{},{},1.5,{},{},2.0]",
                i as f64 * size,
                j as f64 * size,
                (i + 1) as f64 * size,
                (j + 1) as f64 * size
            )
        })
        .collect();
    let cells_path = dir.join("cells.json");
    std::fs::write(&cells_path, format!("[{}]", cells.join(","))).unwrap();
    (scene, cells_path)
}

fn sightline(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

fn ok(out: Output) -> Output {
    assert!(
        out.status.success(),
        "sightline failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn sigkill_at_random_moments_then_resume_is_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let (scene, cells) = fixture(dir.path(), 12, 150, 150);
    let whole = dir.path().join("whole.pvs");
    let t = Instant::now();
    ok(sightline(&[
        "build",
        s(&scene),
        "--cells",
        s(&cells),
        "--method",
        "all",
        "-o",
        s(&whole),
        "--quiet",
    ]));
    let full_time = t.elapsed();

    let out = dir.path().join("killed.pvs");
    let journal = dir.path().join("killed.pvs.journal");
    let mut rng = sightline_stats::Rng::new(0x5eed);
    let (mut kills, mut kills_with_journal) = (0, 0);
    // Kills land at a random moment of a full build's time, scaled down whenever a run
    // finishes before its kill (a loaded machine makes the first timing unreliable): then
    // the finished file is thrown away and the sequence starts over.
    let mut scale = 1.0;
    for attempt in 0.. {
        assert!(attempt < 60, "the build never finished");
        let mut child = Command::new(BIN)
            .args([
                "build",
                s(&scene),
                "--cells",
                s(&cells),
                "--method",
                "all",
                "-o",
                s(&out),
                "--resume",
                "--quiet",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Up to ten kills at random moments (a resumed run may finish first); then one
        // run goes to the end.
        if kills < 10 {
            std::thread::sleep(full_time.mul_f64(scale * (0.05 + 0.55 * rng.f64())));
        } else {
            let out = child.wait_with_output().unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            break;
        }
        // Whether the run finished before its kill (successfully), or was killed.
        let finished = match child.try_wait().unwrap() {
            Some(status) => {
                let stderr = child.wait_with_output().unwrap().stderr;
                assert!(status.success(), "{}", String::from_utf8_lossy(&stderr));
                true
            }
            None => {
                let had_journal = journal.exists();
                child.kill().unwrap(); // SIGKILL
                let killed = !child.wait().unwrap().success();
                if killed {
                    kills += 1;
                    kills_with_journal += had_journal as usize;
                }
                !killed
            }
        };
        if finished {
            if kills_with_journal >= 2 {
                break;
            }
            // Finished before two kills mid-build: start over with earlier kills.
            let _ = std::fs::remove_file(&out);
            let _ = std::fs::remove_file(&journal);
            scale *= 0.5;
            kills = 0;
            kills_with_journal = 0;
        }
    }
    assert!(
        kills_with_journal >= 2,
        "only {kills} kills, {kills_with_journal} mid-build (full build {full_time:?})"
    );
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&whole).unwrap());
    assert!(!journal.exists());
}

#[test]
fn shards_auto_from_the_environment_merge_into_the_whole_build() {
    let dir = tempfile::tempdir().unwrap();
    let (scene, cells) = fixture(dir.path(), 6, 9, 7);
    let whole = dir.path().join("whole.pvs");
    ok(sightline(&[
        "build",
        s(&scene),
        "--cells",
        s(&cells),
        "--method",
        "all",
        "-o",
        s(&whole),
    ]));
    let mut shards = Vec::new();
    for i in 0..3 {
        let shard = dir.path().join(format!("s{i}.pvs"));
        let mut cmd = Command::new(BIN);
        let spec = if i == 2 { "2/3" } else { "auto/3" };
        cmd.args([
            "build",
            s(&scene),
            "--cells",
            s(&cells),
            "--method",
            "all",
            "--shard",
            spec,
            "-o",
            s(&shard),
        ]);
        cmd.env_remove("JOB_COMPLETION_INDEX")
            .env_remove("SLURM_ARRAY_TASK_ID");
        match i {
            0 => cmd.env("JOB_COMPLETION_INDEX", "0"),
            1 => cmd.env("SLURM_ARRAY_TASK_ID", "1"),
            _ => &mut cmd,
        };
        ok(cmd.output().unwrap());
        shards.push(shard);
    }
    let merged = dir.path().join("merged.pvs");
    let mut args = vec!["merge"];
    args.extend(shards.iter().rev().map(|p| s(p)));
    args.extend(["-o", s(&merged)]);
    ok(sightline(&args));
    assert_eq!(
        std::fs::read(&merged).unwrap(),
        std::fs::read(&whole).unwrap()
    );

    // A missing shard is a one-line error and writes nothing.
    let bad = dir.path().join("bad.pvs");
    let out = sightline(&["merge", s(&shards[0]), s(&shards[1]), "-o", s(&bad)]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("error: ") && err.contains("in no input") && err.lines().count() == 1,
        "{err}"
    );
    assert!(!bad.exists());

    // auto without an index in the environment.
    let mut cmd = Command::new(BIN);
    cmd.args([
        "build",
        s(&scene),
        "--cells",
        s(&cells),
        "--method",
        "all",
        "--shard",
        "auto/3",
        "-o",
        s(&bad),
    ]);
    let out = cmd
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("JOB_COMPLETION_INDEX"));
}

#[test]
fn query_answers_json_and_damaged_files_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let (scene, cells) = fixture(dir.path(), 5, 4, 4);
    let pvs = dir.path().join("city.pvs");
    ok(sightline(&[
        "build",
        s(&scene),
        "--cells",
        s(&cells),
        "--method",
        "all",
        "-o",
        s(&pvs),
    ]));
    let out = ok(sightline(&[
        "query",
        s(&pvs),
        "--at",
        "30,30,1.7",
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        v["cell"],
        serde_json::json!([25.0, 25.0, 1.5, 50.0, 50.0, 2.0])
    );
    assert_eq!(v["visible"].as_array().unwrap().len(), 25);

    let out = sightline(&["query", s(&pvs), "--at=-30,30,1.7"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("no cell"));

    let bytes = std::fs::read(&pvs).unwrap();
    let cut = dir.path().join("cut.pvs");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let flipped = dir.path().join("flipped.pvs");
    let mut b = bytes.clone();
    b[170] ^= 0x40; // inside the HEAD section, checked on open
    std::fs::write(&flipped, &b).unwrap();
    for (file, what) in [(&cut, "truncated"), (&flipped, "checksum mismatch")] {
        let out = sightline(&["query", s(file), "--at", "30,30,1.7"]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.starts_with("error: ") && err.contains(what) && err.lines().count() == 1,
            "{err}"
        );
    }
}

#[test]
fn check_samples_cells_of_a_pvs_file_and_refuses_another_scene() {
    let dir = tempfile::tempdir().unwrap();
    let (scene, cells) = fixture(dir.path(), 4, 3, 3);
    let pvs = dir.path().join("city.pvs");
    ok(sightline(&[
        "build",
        s(&scene),
        "--cells",
        s(&cells),
        "--method",
        "all",
        "-o",
        s(&pvs),
    ]));
    let out = ok(sightline(&[
        "check",
        s(&scene),
        s(&pvs),
        "--cells",
        "2",
        "--json",
        "--quiet",
    ]));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cells"], 2);
    assert_eq!(v["missed"], 0);
    assert_eq!(v["method"], "all");

    let other_dir = dir.path().join("other");
    std::fs::create_dir(&other_dir).unwrap();
    let (other, _) = fixture(&other_dir, 5, 3, 3);
    let out = sightline(&["check", s(&other), s(&pvs), "--cells", "2"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("error: ") && err.contains("another scene"),
        "{err}"
    );
}

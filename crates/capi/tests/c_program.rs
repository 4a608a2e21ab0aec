//! `tests/c/query.c`, compiled with the system's C compiler and linked to the static
//! `libsightline.a` this test was built with, answers as `sightline query` (the
//! `sightline-pvs` reader) at every probed point of a small generated city: same cell,
//! same visible ids; its gameplay answers equal the runtime's; and bad inputs (NULL
//! pointers, a truncated file, a non-UTF-8 path) come back as error codes.

use sightline_geom::DVec3;
use sightline_pvs::PvsFile;
use sightline_runtime::{Pvs, Query};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

/// The static library `libsightline.a` of the build this test belongs to: cargo builds the
/// library with every crate type of its manifest (`cdylib`, `staticlib`, `rlib`) in one
/// compilation, and the names of those outputs carry no hash, so the archive lies beside
/// this test's executable in `deps/`. No second cargo invocation (which would resolve
/// features for this package alone and compile its dependencies again).
fn static_lib() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let lib = exe.parent().unwrap().join("libsightline.a");
    assert!(
        lib.exists(),
        "{} is missing: cargo builds it with this test (crate-type staticlib)",
        lib.display()
    );
    lib
}

fn compile(dir: &Path) -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let exe = dir.join("query");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let out = Command::new(&cc)
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-O1", "-I"])
        .arg(here.join("include"))
        .arg(here.join("tests/c/query.c"))
        .arg(static_lib())
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(&exe)
        .output()
        .unwrap_or_else(|e| panic!("cannot run the C compiler {cc}: {e}"));
    assert!(
        out.status.success(),
        "C compile failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    exe
}

fn city_pvs(path: &Path) {
    let scene = Arc::new(sightline_scene::generate::city(5, 50));
    let cells = sightline_scene::cells::grid_cells(&scene, 25.0, 1.5, 2.0).unwrap();
    let method = sightline_methods::create(
        "dual-ray",
        scene.clone(),
        &sightline_methods::MethodOptions::default(),
    )
    .unwrap();
    let opts = sightline_pvs::BuildOptions::default();
    sightline_pvs::build(&scene, &*method, &cells, path, &opts, &|_, _| {}).unwrap();
}

fn ids(words: &mut std::slice::Iter<&str>, name: &str) -> Vec<u32> {
    assert_eq!(words.next(), Some(&name));
    let n: usize = words.next().unwrap().parse().unwrap();
    (0..n)
        .map(|_| words.next().unwrap().parse().unwrap())
        .collect()
}

#[test]
fn the_c_program_answers_as_sightline_query() {
    let dir = std::env::temp_dir().join(format!("sightline-capi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exe = compile(&dir);
    let pvs_path = dir.join("city.pvs");
    city_pvs(&pvs_path);
    let bytes = std::fs::read(&pvs_path).unwrap();
    let truncated = dir.join("truncated.pvs");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();

    let file = PvsFile::open(&pvs_path).unwrap();
    let mut points: Vec<[f64; 3]> = Vec::new();
    for c in file.cells() {
        let (a, b) = (c.min, c.max);
        points.push(((a + b) * 0.5).to_array());
        points.push(a.to_array());
        points.push([b.x, a.y, 1.75]);
        points.push([a.x - 3.0, a.y + 1.0, 1.6]);
    }
    points.push([1e9, 0.0, 1.7]);
    let text: String = points
        .iter()
        .map(|p| format!("{:?} {:?} {:?}\n", p[0], p[1], p[2]))
        .collect();
    let points_path = dir.join("points.txt");
    std::fs::write(&points_path, text).unwrap();

    let out = Command::new(&exe)
        .arg(&pvs_path)
        .arg(&points_path)
        .arg(&truncated)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "the C program failed: {}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );

    let runtime = Pvs::from_vec(bytes).unwrap();
    let mut q = Query::new();
    let mut lines = stdout.lines();
    assert_eq!(
        lines.next().unwrap(),
        format!("version {} abi 1", env!("CARGO_PKG_VERSION"))
    );
    let (mut seeing, mut secondary, mut around) = (Vec::new(), Vec::new(), Vec::new());
    let mut located = 0;
    for (i, p) in points.iter().enumerate() {
        let line = lines.next().unwrap();
        let words: Vec<&str> = line.split(' ').collect();
        assert_eq!(words[..2], ["point", &i.to_string()[..]], "{line}");
        let Some(cell) = file.locate(DVec3::from_array(*p)) else {
            assert_eq!(words[2], "none", "point {p:?}: {line}");
            continue;
        };
        located += 1;
        assert_eq!(words[2..4], ["cell", &cell.to_string()[..]], "point {p:?}");
        let mut w = words[4..].iter();
        assert_eq!(
            ids(&mut w, "visible"),
            file.pvs(cell).unwrap(),
            "point {p:?}"
        );
        let c = cell as u32;
        runtime.cells_seeing_into(&mut q, c, &mut seeing).unwrap();
        assert_eq!(ids(&mut w, "seeing"), seeing);
        runtime.secondary_into(&mut q, c, &mut secondary).unwrap();
        assert_eq!(ids(&mut w, "secondary"), secondary);
        runtime.neighbours_into(c, &mut around);
        assert_eq!(ids(&mut w, "neighbours"), around);
        assert_eq!(w.next(), Some(&"can_see"));
        for pair in w {
            let (b, s) = pair.split_once(':').unwrap();
            let b: u32 = b.parse().unwrap();
            assert_eq!(
                s == "1",
                runtime.can_see(&mut q, c, b).unwrap(),
                "{c} sees {b}"
            );
        }
    }
    assert!(located >= file.cells().len(), "{located} points located");
    assert_eq!(lines.next(), Some("errors ok"));
    std::fs::remove_dir_all(&dir).unwrap();
}

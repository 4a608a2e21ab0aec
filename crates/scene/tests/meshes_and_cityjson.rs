//! CityJSON (0.8 zip, 1.1, 2.0), OBJ and glTF/GLB importers on hand-made fixtures and
//! the real Den Haag tile, with hand-checked facts.

use sightline_geom::{DVec2, DVec3};
use sightline_scene::import::{load, ImportOptions};
use sightline_scene::{Geometry, Object, ObjectKind, Prism, Scene};
use std::path::PathBuf;

fn path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn load_ok(rel: &str) -> Scene {
    load(&path(rel), &ImportOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn vertices(o: &Object) -> Vec<DVec3> {
    match &o.geometry {
        Geometry::Mesh(m) => m.vertices.clone(),
        Geometry::Blocks(ps) => ps
            .iter()
            .flat_map(|p| {
                p.footprint
                    .exterior
                    .iter()
                    .flat_map(|v| [v.extend(p.base), v.extend(p.top)])
                    .collect::<Vec<_>>()
            })
            .collect(),
        Geometry::Flat(ps) => ps
            .iter()
            .flat_map(|p| p.exterior.iter().map(|v| v.extend(0.0)))
            .collect(),
    }
}

fn in_prisms(prisms: &[Prism], p: DVec3) -> bool {
    prisms
        .iter()
        .any(|q| p.z >= q.base && p.z <= q.top && q.footprint.contains(p.truncate()))
}

/// Outer contains every vertex; inner lies within outer (sampled on a grid).
fn check_bounds(o: &Object) {
    // Blocks: outer is the geometry itself (vertices lie on its boundary).
    let mesh_vertices = if o.kind() == ObjectKind::Mesh {
        vertices(o)
    } else {
        vec![]
    };
    for v in mesh_vertices {
        let v = DVec3::new(v.x, v.y, v.z.max(0.0));
        assert!(
            in_prisms(&o.outer, v),
            "{:?}: vertex {v} outside outer",
            o.name
        );
    }
    for q in &o.inner {
        let b = q.footprint.bbox();
        for i in 0..=8 {
            for j in 0..=8 {
                let p = DVec2::new(
                    b.min.x + b.size().x * i as f64 / 8.0,
                    b.min.y + b.size().y * j as f64 / 8.0,
                );
                if q.footprint.contains(p) {
                    for z in [q.base, q.top] {
                        assert!(
                            in_prisms(&o.outer, p.extend(z)),
                            "{:?}: inner {p} outside outer",
                            o.name
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn cityjson_v11_and_v20_parts_lods_and_ground() {
    for file in [
        "tests/fixtures/two_buildings_v11.city.json",
        "tests/fixtures/two_buildings_v20.city.json",
    ] {
        let s = load_ok(file);
        // Key order: B1-podium, B1-tower, B2; the terrain is skipped with a warning.
        let names: Vec<_> = s.objects.iter().map(|o| o.name.clone().unwrap()).collect();
        assert_eq!(names, ["B1-podium", "B1-tower", "B2"]);
        assert_eq!(s.warning_counts(), vec![("skipped-object".to_string(), 1)]);
        let (podium, tower, b2) = (&s.objects[0], &s.objects[1], &s.objects[2]);
        // LoD2.2 beats the LoD0 surface; parts are meshes grounded on the building's base.
        assert_eq!(podium.kind(), ObjectKind::Mesh);
        assert!(
            (podium.bounds.min.z - 0.0).abs() < 1e-9 && (podium.bounds.max.z - 3.0).abs() < 1e-9
        );
        assert!(
            (tower.bounds.min.z - 3.0).abs() < 1e-9 && (tower.bounds.max.z - 33.0).abs() < 1e-9
        );
        assert!(
            (podium.bounds.min.x - 1000.0).abs() < 1e-9
                && (podium.bounds.max.y - 2010.0).abs() < 1e-9
        );
        // Inner bounds: the whole box minus a 2 cm margin, floor to roof.
        assert_eq!(podium.inner.len(), 1);
        assert!((podium.inner[0].top - 3.0).abs() < 1e-9 && podium.inner[0].base == 0.0);
        assert!(
            podium.inner[0].footprint.area() > 198.5 && podium.inner[0].footprint.area() < 200.0
        );
        assert_eq!(tower.inner.len(), 1);
        assert!(
            (tower.inner[0].base - 3.0).abs() < 1e-9 && (tower.inner[0].top - 33.0).abs() < 1e-9
        );
        // LoD1.2 → a block 10 × 10 × 6 m.
        assert_eq!(b2.kind(), ObjectKind::Blocks);
        assert!((b2.bounds.max.z - 6.0).abs() < 1e-9);
        let Geometry::Blocks(ps) = &b2.geometry else {
            unreachable!()
        };
        assert!((ps.iter().map(|p| p.footprint.area()).sum::<f64>() - 100.0).abs() < 1e-3);
        s.objects.iter().for_each(check_bounds);
    }
}

#[test]
fn cityjson_denhaag_zip_v08() {
    let s = load_ok("../../data/cityjson_DenHaag_01.zip");
    // 1,653 BuildingParts + 337 Buildings with their own LoD2 solid; the TINRelief and
    // the 507 part-only Buildings yield no object.
    assert_eq!(s.len(), 1990);
    assert!(s.objects.iter().all(|o| o.kind() == ObjectKind::Mesh));
    assert!(s
        .warnings
        .iter()
        .any(|w| w.kind == "skipped-object" && w.message.contains("TINRelief")));
    // Grounded: every building stands on z = 0; roofs up to ~35 m above it.
    assert!(s.bounds.min.z.abs() < 1e-9, "{:?}", s.bounds);
    assert!(
        s.bounds.max.z > 20.0 && s.bounds.max.z < 36.0,
        "{:?}",
        s.bounds
    );
    assert!(s
        .objects
        .iter()
        .all(|o| o.outer.iter().all(|p| p.top >= p.base)));
    // Most parts are closed solids and get an inner bound.
    let with_inner = s.objects.iter().filter(|o| !o.inner.is_empty()).count();
    assert!(with_inner > s.len() / 2, "{with_inner} of {}", s.len());
    for o in s.objects.iter().step_by(37) {
        check_bounds(o);
    }
    // Hand-checked (python on the raw file): part _1 of GUID_DBDABF53…: a 1.39 m² flat-roofed
    // box, floor at 4.583 m and roof at 7.717 m, in a building whose lowest point is 4.496 m.
    let o = s
        .objects
        .iter()
        .find(|o| o.name.as_deref() == Some("GUID_DBDABF53-7DD5-4C2F-BE7F-51F29A0CBA16_1"))
        .unwrap();
    assert!((o.bounds.min.z - 0.087).abs() < 1e-6 && (o.bounds.max.z - 3.221).abs() < 1e-6);
    assert!(
        (o.bounds.min.x - 78613.525).abs() < 1e-6 && (o.bounds.max.y - 457986.069).abs() < 1e-6
    );
    assert_eq!(o.inner.len(), 1);
    let i = &o.inner[0];
    assert!((i.base - 0.087).abs() < 1e-6 && (i.top - 3.221).abs() < 1e-6);
    assert!(i.footprint.area() > 1.2 && i.footprint.area() < 1.3883);
    check_bounds(o);
}

#[test]
fn obj_objects_become_meshes_z_up() {
    let s = load_ok("tests/fixtures/two_boxes.obj");
    let names: Vec<_> = s.objects.iter().map(|o| o.name.clone().unwrap()).collect();
    assert_eq!(names, ["tower", "slab", "leaf"]);
    // y-up 0..30 becomes z 0..30; z 0..10 becomes y -10..0.
    let t = &s.objects[0];
    assert_eq!((t.bounds.min.z, t.bounds.max.z), (0.0, 30.0));
    assert_eq!((t.bounds.min.y, t.bounds.max.y), (-10.0, 0.0));
    assert_eq!(t.inner.len(), 1);
    assert_eq!(t.inner[0].top, 30.0);
    // A single triangle is open: no inner bound, but an outer one.
    assert!(s.objects[2].inner.is_empty() && !s.objects[2].outer.is_empty());
    s.objects.iter().for_each(check_bounds);
}

#[test]
fn gltf_and_glb_apply_node_transforms() {
    for file in ["tests/fixtures/boxes.gltf", "tests/fixtures/boxes.glb"] {
        let s = load_ok(file);
        let names: Vec<_> = s.objects.iter().map(|o| o.name.clone().unwrap()).collect();
        assert_eq!(names, ["parent", "child"]);
        // parent: unit box at x+100; y-up → z-up.
        let p = s.objects[0].bounds;
        assert_eq!(
            (p.min.x, p.max.x, p.min.z, p.max.z),
            (100.0, 101.0, 0.0, 1.0)
        );
        assert_eq!((p.min.y, p.max.y), (-1.0, 0.0));
        // child: translate (0,0,-10) then scale (2,3,2) under the parent: x 100..102,
        // glTF y 0..3 → z 0..3, glTF z -10..-8 → y 8..10.
        let c = s.objects[1].bounds;
        assert_eq!(
            (c.min.x, c.max.x, c.min.z, c.max.z),
            (100.0, 102.0, 0.0, 3.0)
        );
        assert_eq!((c.min.y, c.max.y), (8.0, 10.0));
        s.objects.iter().for_each(check_bounds);
    }
}

//! OpenStreetMap `.osm.pbf` importer (osmpbf): closed ways and `type=multipolygon`
//! relations tagged `building` (any value but `no`) or `building:part`.
//!
//! * Height: `height` (units: "12", "12 m", "40 ft", "12'6\""), else `building:levels` ×
//!   3 m (warning `height-from-levels`), else 9 m (warning `height-default`); base:
//!   `min_height`, else `building:min_level` × 3 m, else 0 — the rules of
//!   [`super::height::resolve`], shared with GeoJSON.
//! * Multipolygon rings are assembled from member ways joined end to end (`outer` and
//!   `inner` roles); each outer ring takes the inner rings inside it as holes.
//! * lon/lat are projected with the local transverse Mercator of [`super::project`],
//!   centred on the buildings' bounding box.
//! * Objects: buildings from ways in way order, then from relations in relation order
//!   (the file's order, which osmium sorts by id); the name is `way/ID` / `relation/ID`
//!   (`name` tag in the message of warnings). Warnings name the object's position.

use super::height::{self, HeightProps, Num};
use super::project::LocalTransverseMercator;
use super::validate::{self, Diagnostics};
use super::{ImportError, ImportOptions};
use crate::{Object, Prism, Scene};
use osmpbf::{Element, ElementReader, RelMemberType};
use sightline_geom::{Aabb2, DVec2, Polygon};
use std::collections::HashMap;

struct Building {
    name: String,
    tags: HashMap<String, String>,
    /// Rings of node ids: outer rings, then holes per outer resolved later.
    outers: Vec<Vec<i64>>,
    inners: Vec<Vec<i64>>,
}

fn is_building(tags: &HashMap<String, String>) -> bool {
    tags.get("building").is_some_and(|v| v != "no") || tags.contains_key("building:part")
}

fn tag_num(tags: &HashMap<String, String>, k: &str) -> Num {
    match tags.get(k) {
        None => Num::Missing,
        Some(v) => match height::parse_length(v) {
            Some(x) => Num::Value(x),
            None => Num::Invalid(format!("\"{v}\"")),
        },
    }
}

/// Join way node lists into closed rings; returns the rings and whether some way
/// could not be closed.
fn assemble(mut ways: Vec<Vec<i64>>) -> (Vec<Vec<i64>>, bool) {
    let mut rings = Vec::new();
    let mut broken = false;
    ways.retain(|w| w.len() >= 2);
    while let Some(mut ring) = ways.pop() {
        loop {
            if ring.len() > 2 && ring.first() == ring.last() {
                break;
            }
            let end = *ring.last().unwrap_or(&0);
            let Some(k) = ways
                .iter()
                .position(|w| w.first() == Some(&end) || w.last() == Some(&end))
            else {
                broken = true;
                break;
            };
            let mut w = ways.swap_remove(k);
            if w.first() != Some(&end) {
                w.reverse();
            }
            ring.extend(w.into_iter().skip(1));
        }
        if ring.len() > 3 && ring.first() == ring.last() {
            rings.push(ring);
        }
    }
    (rings, broken)
}

/// Parse `.osm.pbf` bytes.
pub fn parse(bytes: &[u8], opts: &ImportOptions) -> Result<Scene, ImportError> {
    let mut nodes: HashMap<i64, DVec2> = HashMap::new();
    let mut way_refs: HashMap<i64, Vec<i64>> = HashMap::new();
    let mut buildings: Vec<Building> = Vec::new();
    let mut relations: Vec<Building> = Vec::new();
    let mut rel_members: Vec<Vec<(i64, String)>> = Vec::new();
    let to_map = |it: &mut dyn Iterator<Item = (&str, &str)>| -> HashMap<String, String> {
        it.map(|(k, v)| (k.to_string(), v.to_string())).collect()
    };
    ElementReader::new(std::io::Cursor::new(bytes))
        .for_each(|e| match e {
            Element::Node(n) => {
                nodes.insert(n.id(), DVec2::new(n.lon(), n.lat()));
            }
            Element::DenseNode(n) => {
                nodes.insert(n.id(), DVec2::new(n.lon(), n.lat()));
            }
            Element::Way(w) => {
                let refs: Vec<i64> = w.refs().collect();
                let tags = to_map(&mut w.tags());
                if is_building(&tags) {
                    buildings.push(Building {
                        name: format!("way/{}", w.id()),
                        tags,
                        outers: vec![refs.clone()],
                        inners: vec![],
                    });
                }
                way_refs.insert(w.id(), refs);
            }
            Element::Relation(r) => {
                let tags = to_map(&mut r.tags());
                if is_building(&tags)
                    && tags.get("type").map(String::as_str) == Some("multipolygon")
                {
                    rel_members.push(
                        r.members()
                            .filter(|m| m.member_type == RelMemberType::Way)
                            .map(|m| (m.member_id, m.role().unwrap_or("").to_string()))
                            .collect(),
                    );
                    relations.push(Building {
                        name: format!("relation/{}", r.id()),
                        tags,
                        outers: vec![],
                        inners: vec![],
                    });
                }
            }
        })
        .map_err(|e| ImportError::Format(format!("invalid OSM PBF: {e}")))?;

    let mut diag = Diagnostics::new(opts.strict);
    for (rel, members) in relations.iter_mut().zip(rel_members) {
        let (mut outer, mut inner) = (Vec::new(), Vec::new());
        for (id, role) in members {
            if let Some(refs) = way_refs.get(&id) {
                if role == "inner" {
                    inner.push(refs.clone());
                } else {
                    outer.push(refs.clone());
                }
            }
        }
        let (o, b1) = assemble(outer);
        let (i, b2) = assemble(inner);
        if b1 || b2 {
            diag.warn(
                "ring-not-closed",
                None,
                format!(
                    "{}: member ways do not form closed rings; open pieces dropped",
                    rel.name
                ),
            );
        }
        rel.outers = o;
        rel.inners = i;
    }
    buildings.extend(relations);

    // Resolve node ids to lon/lat; project around the buildings' centre.
    let mut resolved: Vec<(usize, Vec<Vec<Vec<DVec2>>>)> = Vec::new();
    let mut bbox = Aabb2::EMPTY;
    for (index, b) in buildings.iter().enumerate() {
        // Extracts cut ways at their border and real data has broken parts: a building
        // that cannot be resolved is skipped (counted), the rest of the city loads.
        let resolve = || -> Result<Vec<Vec<Vec<DVec2>>>, ImportError> {
            let ring = |ids: &Vec<i64>| -> Result<Vec<DVec2>, ImportError> {
                ids.iter()
                    .map(|id| {
                        nodes.get(id).copied().ok_or_else(|| ImportError::Feature {
                            index,
                            message: format!("{}: node {id} is missing from the file", b.name),
                        })
                    })
                    .collect()
            };
            let inners: Vec<Vec<DVec2>> = b.inners.iter().map(ring).collect::<Result<_, _>>()?;
            let mut polys = Vec::new();
            for o in &b.outers {
                let o = ring(o)?;
                let probe = Polygon::new(o.clone(), vec![]);
                let mut rings = vec![o];
                rings.extend(
                    inners
                        .iter()
                        .filter(|h| h.iter().any(|p| probe.contains(*p)))
                        .cloned(),
                );
                polys.push(rings);
            }
            if let Some(p) = polys
                .iter()
                .flatten()
                .flatten()
                .find(|p| !(p.x.abs() <= 180.0 && p.y.abs() <= 90.0))
            {
                return Err(ImportError::Feature {
                    index,
                    message: format!("{}: lon/lat {p} out of range", b.name),
                });
            }
            Ok(polys)
        };
        match resolve() {
            Ok(polys) => {
                for p in polys.iter().flatten().flatten() {
                    bbox = bbox.grow(*p);
                }
                resolved.push((index, polys));
            }
            Err(e) => diag.skip(e)?,
        }
    }
    if bbox.is_empty() {
        return Err(diag.nothing_left("empty scene: no building way or multipolygon in the file"));
    }
    let proj = LocalTransverseMercator::centred_on(bbox.min, bbox.max);
    let mut objects = Vec::new();
    for (index, polys) in resolved {
        let b = &buildings[index];
        let hp = HeightProps {
            height: tag_num(&b.tags, "height"),
            min_height: tag_num(&b.tags, "min_height"),
            levels: tag_num(&b.tags, "building:levels"),
            min_level: tag_num(&b.tags, "building:min_level"),
        };
        let rejected = |m: String| ImportError::Feature {
            index,
            message: format!("{}: {m}", b.name),
        };
        let extent = match height::resolve(&hp, index, &mut diag) {
            Ok(e) => e,
            Err(m) => {
                diag.skip(rejected(m))?;
                continue;
            }
        };
        let mut footprints = Vec::new();
        let mut broken = false;
        for rings in polys {
            let rings = rings
                .into_iter()
                .map(|r| r.into_iter().map(|p| proj.project(p.x, p.y)).collect())
                .collect();
            match validate::polygon(rings, true, index, &mut diag) {
                Ok(f) => footprints.extend(f),
                Err(m) => {
                    diag.skip(rejected(m))?;
                    broken = true;
                    break;
                }
            }
        }
        if broken {
            continue;
        }
        if footprints.is_empty() {
            diag.warn(
                "degenerate-ring",
                Some(index),
                format!("{}: no valid footprint, skipped", b.name),
            );
            continue;
        }
        let name = Some(b.name.clone());
        objects.push(match extent {
            height::Extent::Flat => Object::flat(name, footprints),
            height::Extent::Prism { base, top } => Object::blocks(
                name,
                footprints
                    .into_iter()
                    .map(|f| Prism::new(f.normalized(), base, top))
                    .collect(),
            ),
        });
    }
    if objects.is_empty() {
        return Err(diag.nothing_left("empty scene: no valid building footprint"));
    }
    let mut scene = Scene::from_objects(objects);
    scene.warnings = diag.warnings;
    Ok(scene)
}

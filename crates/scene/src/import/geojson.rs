//! GeoJSON importer: a FeatureCollection of Polygon / MultiPolygon features.
//!
//! * `height` = top (m, number or string with a unit); `min_height` = base (default 0);
//!   `building:levels` (or `levels`) × 3 m stands in for a missing height (warning
//!   `height-from-levels`), else 9 m (warning `height-default`).
//! * height 0 or `"kind": "street"` → a flat object.
//! * name = the feature's `id` (string or number), else property `name`.
//! * Coordinates are projected metres, used as they are, or WGS84 lon/lat — detected
//!   (see [`super::project::looks_like_wgs84`], a top-level `crs` naming CRS84/EPSG:4326,
//!   or forced with [`Crs::Wgs84`]) and projected with a local transverse Mercator centred
//!   on the data ([`super::project`]).
//! * Features without geometry or with other geometry types are skipped (warning
//!   `unsupported-geometry`), so object ids count only the imported features; warnings and
//!   errors name the *feature* index in the file.

use super::height::{self, json_length, Extent, HeightProps};
use super::project::{looks_like_wgs84, LocalTransverseMercator};
use super::validate::{self, Diagnostics};
use super::{Crs, ImportError, ImportOptions};
use crate::{Object, Prism, Scene};
use serde_json::Value;
use sightline_geom::{Aabb2, DVec2, Polygon};

type Rings = Vec<Vec<DVec2>>;

struct RawFeature {
    index: usize,
    name: Option<String>,
    extent: Extent,
    polygons: Vec<Rings>,
}

fn feature_err(index: usize, message: impl Into<String>) -> ImportError {
    ImportError::Feature {
        index,
        message: message.into(),
    }
}

/// Parse GeoJSON text.
pub fn parse(bytes: &[u8], opts: &ImportOptions) -> Result<Scene, ImportError> {
    let root: Value = serde_json::from_slice(bytes)
        .map_err(|e| ImportError::Format(format!("invalid JSON: {e}")))?;
    from_value(&root, opts)
}

fn position(v: &Value, index: usize) -> Result<DVec2, ImportError> {
    let arr = v
        .as_array()
        .filter(|a| a.len() >= 2)
        .ok_or_else(|| feature_err(index, format!("position {v} is not [x, y]")))?;
    let num = |c: &Value| {
        c.as_f64()
            .ok_or_else(|| feature_err(index, format!("coordinate {c} is not a number")))
    };
    Ok(DVec2::new(num(&arr[0])?, num(&arr[1])?))
}

fn rings(v: &Value, index: usize) -> Result<Rings, ImportError> {
    let arr = v
        .as_array()
        .ok_or_else(|| feature_err(index, "polygon coordinates are not an array of rings"))?;
    arr.iter()
        .map(|ring| {
            ring.as_array()
                .ok_or_else(|| feature_err(index, "ring is not an array of positions"))?
                .iter()
                .map(|p| position(p, index))
                .collect()
        })
        .collect()
}

/// Whether a top-level `crs` member (GeoJSON 2008) names WGS84 lon/lat, if present.
fn declared_wgs84(root: &Value) -> Option<bool> {
    if root.get("local_frame").is_some() {
        return Some(false);
    }
    let name = root.get("crs")?.get("properties")?.get("name")?.as_str()?;
    let n = name.to_ascii_uppercase();
    Some(n.contains("CRS84") || n.ends_with("EPSG::4326") || n.ends_with("EPSG:4326"))
}

/// Import a parsed GeoJSON document.
pub fn from_value(root: &Value, opts: &ImportOptions) -> Result<Scene, ImportError> {
    match root.get("type").and_then(Value::as_str) {
        Some("FeatureCollection") => {}
        Some(t) => {
            return Err(ImportError::Format(format!(
                "expected a GeoJSON FeatureCollection, found type \"{t}\""
            )))
        }
        None => {
            return Err(ImportError::Format(
                "expected a GeoJSON FeatureCollection (no \"type\" member)".into(),
            ))
        }
    }
    let features = root
        .get("features")
        .and_then(Value::as_array)
        .ok_or_else(|| {
            ImportError::Format("FeatureCollection without a \"features\" array".into())
        })?;
    let mut diag = Diagnostics::new(opts.strict);
    let mut raw = Vec::with_capacity(features.len());
    for (index, f) in features.iter().enumerate() {
        match read_feature(f, index, &mut diag) {
            Ok(Some(r)) => raw.push(r),
            Ok(None) => {}
            Err(e) => diag.skip(e)?,
        }
    }
    let empty = || {
        format!(
            "empty scene: no Polygon or MultiPolygon feature among {} feature(s)",
            features.len()
        )
    };
    if raw.is_empty() {
        return Err(diag.nothing_left(empty()));
    }

    let bbox = raw
        .iter()
        .flat_map(|r| r.polygons.iter().flatten().flatten())
        .fold(Aabb2::EMPTY, |b, p| b.grow(*p));
    let wgs84 = match opts.crs {
        Crs::Wgs84 => true,
        Crs::Projected => false,
        Crs::Auto => declared_wgs84(root).unwrap_or_else(|| looks_like_wgs84(bbox.min, bbox.max)),
    };
    if wgs84 {
        if !looks_like_wgs84(bbox.min, bbox.max) && opts.crs == Crs::Wgs84 {
            // Forced but not lon/lat-like: still refuse absurd values.
            if !(bbox.min.x >= -180.0
                && bbox.max.x <= 180.0
                && bbox.min.y >= -90.0
                && bbox.max.y <= 90.0)
            {
                return Err(ImportError::Format(format!(
                    "coordinates [{}, {}]..[{}, {}] are not WGS84 longitude/latitude",
                    bbox.min.x, bbox.min.y, bbox.max.x, bbox.max.y
                )));
            }
        }
        let proj = LocalTransverseMercator::centred_on(bbox.min, bbox.max);
        for r in &mut raw {
            for ring in r.polygons.iter_mut().flatten().flatten() {
                *ring = proj.project(ring.x, ring.y);
            }
        }
    }

    let mut objects = Vec::with_capacity(raw.len());
    'features: for r in raw {
        let mut polys: Vec<Polygon> = Vec::new();
        for rings in r.polygons {
            match validate::polygon(rings, true, r.index, &mut diag) {
                Ok(p) => polys.extend(p),
                Err(m) => {
                    diag.skip(feature_err(r.index, m))?;
                    continue 'features;
                }
            }
        }
        if polys.is_empty() {
            diag.skip(feature_err(
                r.index,
                "no valid polygon left (all rings degenerate or zero-area)",
            ))?;
            continue;
        }
        objects.push(match r.extent {
            Extent::Flat => Object::flat(r.name, polys),
            Extent::Prism { base, top } => Object::blocks(
                r.name,
                polys
                    .into_iter()
                    .map(|p| Prism::new(p.normalized(), base, top))
                    .collect(),
            ),
        });
    }
    if objects.is_empty() {
        return Err(diag.nothing_left(empty()));
    }
    let mut scene = Scene::from_objects(objects);
    scene.warnings = diag.warnings;
    Ok(scene)
}

fn read_feature(
    f: &Value,
    index: usize,
    diag: &mut Diagnostics,
) -> Result<Option<RawFeature>, ImportError> {
    if f.get("type").and_then(Value::as_str) != Some("Feature") {
        return Err(feature_err(index, "not a GeoJSON Feature"));
    }
    let props = match f.get("properties") {
        None | Some(Value::Null) => None,
        Some(Value::Object(m)) => Some(m),
        Some(_) => return Err(feature_err(index, "\"properties\" is not an object")),
    };
    let prop = |k: &str| props.and_then(|m| m.get(k));
    let geom = match f.get("geometry") {
        None | Some(Value::Null) => {
            diag.warn(
                "unsupported-geometry",
                Some(index),
                "feature without geometry skipped",
            );
            return Ok(None);
        }
        Some(g) => g,
    };
    let coords = geom.get("coordinates");
    let polygons: Vec<Rings> = match geom.get("type").and_then(Value::as_str) {
        Some("Polygon") => vec![rings(
            coords.ok_or_else(|| feature_err(index, "Polygon without coordinates"))?,
            index,
        )?],
        Some("MultiPolygon") => coords
            .and_then(Value::as_array)
            .ok_or_else(|| feature_err(index, "MultiPolygon coordinates are not an array"))?
            .iter()
            .map(|p| rings(p, index))
            .collect::<Result<_, _>>()?,
        Some(t) => {
            diag.warn(
                "unsupported-geometry",
                Some(index),
                format!("{t} geometry skipped (only Polygon and MultiPolygon)"),
            );
            return Ok(None);
        }
        None => return Err(feature_err(index, "geometry without a \"type\"")),
    };
    if polygons.is_empty() || polygons.iter().all(|p| p.is_empty()) {
        return Err(feature_err(index, "empty geometry"));
    }
    let name = match f.get("id") {
        Some(Value::String(s)) => Some(s.clone()),
        Some(Value::Number(n)) => Some(n.to_string()),
        _ => prop("name").and_then(Value::as_str).map(str::to_string),
    };
    let is_street = prop("kind").and_then(Value::as_str) == Some("street");
    let extent = if is_street {
        Extent::Flat
    } else {
        let levels = match json_length(prop("building:levels")) {
            height::Num::Missing => json_length(prop("levels")),
            n => n,
        };
        let hp = HeightProps {
            height: json_length(prop("height")),
            min_height: json_length(prop("min_height")),
            levels,
            min_level: json_length(prop("building:min_level")),
        };
        height::resolve(&hp, index, diag).map_err(|m| feature_err(index, m))?
    };
    Ok(Some(RawFeature {
        index,
        name,
        extent,
        polygons,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(s: &str) -> Result<Scene, ImportError> {
        parse(s.as_bytes(), &ImportOptions::default())
    }

    const SQ: &str = "[[[0,0],[10,0],[10,10],[0,10],[0,0]]]";

    fn fc(features: &[String]) -> String {
        format!(
            "{{\"type\":\"FeatureCollection\",\"features\":[{}]}}",
            features.join(",")
        )
    }

    fn feat(props: &str, coords: &str) -> String {
        format!("{{\"type\":\"Feature\",\"properties\":{props},\"geometry\":{{\"type\":\"Polygon\",\"coordinates\":{coords}}}}}")
    }

    #[test]
    fn block_flat_and_levels() {
        let s = load(&fc(&[
            feat("{\"height\":12,\"min_height\":2,\"name\":\"a\"}", SQ),
            feat("{\"height\":0}", SQ),
            feat("{\"kind\":\"street\",\"height\":5}", SQ),
            feat("{\"building:levels\":4}", SQ),
            feat("{\"height\":\"40 ft\"}", SQ),
        ]))
        .unwrap();
        assert_eq!(s.len(), 5);
        assert_eq!(s.objects[0].name.as_deref(), Some("a"));
        assert_eq!(s.objects[0].bounds.min.z, 2.0);
        assert_eq!(s.objects[0].bounds.max.z, 12.0);
        assert_eq!(s.objects[1].kind(), crate::ObjectKind::Flat);
        assert_eq!(s.objects[2].kind(), crate::ObjectKind::Flat);
        assert_eq!(s.objects[3].bounds.max.z, 12.0);
        assert!((s.objects[4].bounds.max.z - 12.192).abs() < 1e-9);
        assert_eq!(
            s.warning_counts(),
            vec![("height-from-levels".to_string(), 1)]
        );
    }

    #[test]
    fn errors_name_the_feature() {
        let cases = [
            (feat("{\"height\":-3}", SQ), "negative height"),
            (feat("{\"height\":\"NaN\"}", SQ), "not a number"),
            (feat("{\"height\":5,\"min_height\":5}", SQ), "not below"),
            (
                feat("{\"height\":5}", "[[[0,0],[\"a\",0],[1,1],[0,0]]]"),
                "not a number",
            ),
            (
                feat("{\"height\":5}", "[[[0,0],[1e300,0],[1,1],[0,0]]]"),
                "out of range",
            ),
        ];
        let strict = ImportOptions {
            strict: true,
            ..ImportOptions::default()
        };
        for (f, what) in cases {
            let text = fc(&[feat("{\"height\":3}", SQ), f.clone()]);
            let e = parse(text.as_bytes(), &strict).unwrap_err();
            let msg = e.to_string();
            assert!(msg.starts_with("feature 1:"), "{msg}");
            assert!(msg.contains(what), "{msg} lacks {what}");
            // By default the bad feature is skipped with a warning naming it, and the
            // good one loads.
            let s = load(&text).unwrap();
            assert_eq!(s.len(), 1);
            let w: Vec<_> = s
                .warnings
                .iter()
                .filter(|w| w.kind == "skipped-feature")
                .collect();
            assert_eq!(w.len(), 1, "{:?}", s.warnings);
            assert_eq!(w[0].feature, Some(1));
            assert!(w[0].message.contains(what), "{}", w[0].message);
            // With nothing else left, the rejection is the error.
            let msg = load(&fc(&[f])).unwrap_err().to_string();
            assert!(msg.starts_with("feature 0:") && msg.contains(what), "{msg}");
        }
    }

    #[test]
    fn file_level_errors() {
        assert!(load("{").unwrap_err().to_string().contains("invalid JSON"));
        assert!(load(&fc(&[]))
            .unwrap_err()
            .to_string()
            .contains("empty scene"));
        let single = feat("{\"height\":3}", SQ);
        assert!(load(&single)
            .unwrap_err()
            .to_string()
            .contains("FeatureCollection"));
    }

    #[test]
    fn wgs84_is_detected_and_projected() {
        let c = "[[[4.830,45.760],[4.831,45.760],[4.831,45.761],[4.830,45.761],[4.830,45.760]]]";
        let s = load(&fc(&[feat("{\"height\":10}", c)])).unwrap();
        let b = s.bounds;
        // 0.001° of longitude at 45.76° ≈ 77.8 m, of latitude ≈ 111.1 m; centred.
        assert!((b.size().x - 77.8).abs() < 0.5, "{:?}", b);
        assert!((b.size().y - 111.1).abs() < 0.5, "{:?}", b);
        assert!(b.center().truncate().length() < 0.1);
        // Forced projected, the same numbers are a sub-millimetre square: unusable.
        let forced = parse(
            fc(&[feat("{\"height\":10}", c)]).as_bytes(),
            &ImportOptions {
                crs: Crs::Projected,
                ..ImportOptions::default()
            },
        );
        assert!(forced.is_err());
    }
}

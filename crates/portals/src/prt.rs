//! qbsp's portal file (`.prt`, format `PRT1`): the portals of a compiled level's world
//! tree, so that a solver starts from the topology qbsp built (as Quake's `vis` does)
//! instead of portalizing the tree again.
//!
//! ```text
//! PRT1
//! <leaves>          number of PRT leaves (= the level's visleafs)
//! <portals>
//! <n> <a> <b> (x y z) (x y z) ...     one line per portal, n >= 3 points
//! ```
//!
//! PRT leaf `k` is BSP leaf `k + 1` (BSP leaf 0 is the shared solid leaf and never
//! appears). The winding is ordered so that vis's plane (`(p0 - p1) × (p2 - p1)`, its
//! normal) points into the first leaf `a`.
//!
//! Guarantee: [`parse_prt`] never panics and never allocates more than a bounded
//! multiple of its input's size; malformed input is a [`PrtError`] naming the line.
//! `PRT2` (detail clusters) and the `PRT1-AM` / `PRT1-Q3` variants are recognized and
//! refused with a clear error.
//!
//! [`prt_from_portals`] and [`Prt::to_text`] write our own portals (from the tree,
//! [`crate::portalize`]) in the same format, so that Quake's `vis` (ericw-tools) and
//! ours start from the same portals on any level, also one without a shipped `.prt`.
//! Coordinates are written in Rust's shortest round-trip form (qbsp prints `%f`, six
//! decimals): reading the text back gives exactly the same `f64`s, planes and leaves.

use crate::portalize::Portal;
use crate::winding::{Plane, Winding};
use sightline_geom::DVec3;
use sightline_scene::import::bsp::BspLevel;

/// Largest coordinate accepted (Quake levels stay within ±32,768; BSP2 levels within
/// a few times that).
const MAX_COORD: f64 = 1e6;
/// Most points on one portal winding (qbsp's `MAX_POINTS_ON_WINDING` is 64; newer
/// tools allow more).
const MAX_POINTS: usize = 1024;

/// One portal of a `.prt`: its winding and its two PRT leaves (`k` = BSP leaf `k + 1`).
#[derive(Clone, Debug, PartialEq)]
pub struct PrtPortal {
    pub points: Vec<[f64; 3]>,
    pub leaves: [u32; 2],
}

/// A parsed `PRT1` file.
#[derive(Clone, Debug, PartialEq)]
pub struct Prt {
    /// Number of PRT leaves (BSP leaves `1 ..= leaves`).
    pub leaves: u32,
    pub portals: Vec<PrtPortal>,
}

/// Why a `.prt` cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PrtError {
    #[error("PRT: line {line}: {what}")]
    Syntax { line: usize, what: String },
    #[error("PRT: {0} files are not supported (only PRT1)")]
    Unsupported(String),
    #[error("PRT: does not match the level: {0}")]
    Mismatch(String),
}

fn syntax(line: usize, what: impl Into<String>) -> PrtError {
    PrtError::Syntax {
        line,
        what: what.into(),
    }
}

/// Parse a `.prt` file's bytes.
pub fn parse_prt(data: &[u8]) -> Result<Prt, PrtError> {
    let text = std::str::from_utf8(data).map_err(|e| {
        let line = 1 + data[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        syntax(line, "not text (invalid UTF-8)")
    })?;
    // Non-empty lines with their 1-based numbers.
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let (n, magic) = lines.next().ok_or_else(|| syntax(1, "empty file"))?;
    match magic {
        "PRT1" => {}
        "PRT2" | "PRT1-AM" | "PRT1-Q3" => return Err(PrtError::Unsupported(magic.into())),
        _ => {
            let shown: String = magic.chars().take(16).collect();
            return Err(syntax(n, format!("expected PRT1, found '{shown}'")));
        }
    }
    let mut count = |what: &str| -> Result<(usize, u32), PrtError> {
        let (n, l) = lines
            .next()
            .ok_or_else(|| syntax(n + 1, format!("missing the {what} count")))?;
        let v = l
            .parse::<u32>()
            .map_err(|_| syntax(n, format!("the {what} count '{l}' is not a number")))?;
        Ok((n, v))
    };
    let (_, leaves) = count("leaf")?;
    let (n_portals_line, n_portals) = count("portal")?;
    // Every portal line holds at least ~20 bytes: bound the allocation by the input.
    if n_portals as usize > data.len() / 8 + 1 {
        return Err(syntax(
            n_portals_line,
            format!("{n_portals} portals cannot fit in {} bytes", data.len()),
        ));
    }
    let mut portals = Vec::with_capacity(n_portals as usize);
    let mut last_line = n_portals_line;
    for k in 0..n_portals {
        let (n, l) = lines.next().ok_or_else(|| {
            syntax(
                last_line + 1,
                format!("the file ends after {k} of {n_portals} portals"),
            )
        })?;
        last_line = n;
        portals.push(parse_portal(n, l, leaves)?);
    }
    if let Some((n, _)) = lines.next() {
        return Err(syntax(
            n,
            format!("unexpected text after the {n_portals} portals"),
        ));
    }
    Ok(Prt { leaves, portals })
}

fn parse_portal(n: usize, l: &str, leaves: u32) -> Result<PrtPortal, PrtError> {
    let (head, rest) = l.split_once('(').unwrap_or((l, ""));
    let ints: Vec<&str> = head.split_whitespace().collect();
    let [np, a, b] = ints[..] else {
        return Err(syntax(
            n,
            "expected '<points> <leaf> <leaf> (x y z) ...'".to_string(),
        ));
    };
    let int = |s: &str, what: &str| {
        s.parse::<u32>()
            .map_err(|_| syntax(n, format!("{what} '{s}' is not a non-negative integer")))
    };
    let np = int(np, "point count")? as usize;
    let (a, b) = (int(a, "leaf")?, int(b, "leaf")?);
    if !(3..=MAX_POINTS).contains(&np) {
        return Err(syntax(
            n,
            format!("{np} points (a portal has 3 to {MAX_POINTS})"),
        ));
    }
    for x in [a, b] {
        if x >= leaves {
            return Err(syntax(
                n,
                format!("leaf {x} is out of range (the file has {leaves} leaves)"),
            ));
        }
    }
    if a == b {
        return Err(syntax(n, format!("a portal from leaf {a} to itself")));
    }
    let mut points = Vec::with_capacity(np);
    let mut rest = format!("({rest}");
    for i in 0..np {
        let r = rest.trim_start();
        let Some(r) = r.strip_prefix('(') else {
            return Err(syntax(n, format!("point {} of {np}: expected '('", i + 1)));
        };
        let Some((inside, after)) = r.split_once(')') else {
            return Err(syntax(n, format!("point {} of {np}: missing ')'", i + 1)));
        };
        let c: Vec<f64> = inside
            .split_whitespace()
            .map(|v| v.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                syntax(
                    n,
                    format!("point {} of {np}: '{inside}' is not x y z", i + 1),
                )
            })?;
        let [x, y, z] = c[..] else {
            return Err(syntax(
                n,
                format!(
                    "point {} of {np}: {} coordinates, expected 3",
                    i + 1,
                    c.len()
                ),
            ));
        };
        if ![x, y, z]
            .iter()
            .all(|v| v.is_finite() && v.abs() <= MAX_COORD)
        {
            return Err(syntax(
                n,
                format!("point {} of {np} is not finite or out of range", i + 1),
            ));
        }
        points.push([x, y, z]);
        rest = after.to_string();
    }
    if !rest.trim().is_empty() {
        return Err(syntax(n, format!("unexpected text after the {np} points")));
    }
    Ok(PrtPortal {
        points,
        leaves: [a, b],
    })
}

impl Prt {
    /// The file's text: `PRT1`, the leaf and portal counts, one line per portal
    /// (`n a b (x y z) ...`), each number in its shortest form that reads back exactly.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = format!("PRT1\n{}\n{}\n", self.leaves, self.portals.len());
        for p in &self.portals {
            let _ = write!(s, "{} {} {}", p.points.len(), p.leaves[0], p.leaves[1]);
            for [x, y, z] in &p.points {
                // `+ 0.0` writes -0 as 0.
                let _ = write!(s, " ({} {} {})", x + 0.0, y + 0.0, z + 0.0);
            }
            s.push('\n');
        }
        s
    }
}

/// Our portals (between BSP leaves, as [`crate::portalize::portalize`] or
/// [`portals_for_level`] give them) as a `.prt` of `visleafs` leaves: PRT leaf `k` =
/// BSP leaf `k + 1`, each winding ordered so that vis's plane points into the first
/// leaf, i.e. so that the portal reads back with the same plane and leaves. Windings of
/// zero area (which [`portals_for_level`] drops) are left out. A portal on leaf 0 or
/// past `visleafs`, or with a point that is not finite or beyond ±10⁶, is an error.
pub fn prt_from_portals(portals: &[Portal], visleafs: u32) -> Result<Prt, PrtError> {
    let mut out = Vec::with_capacity(portals.len());
    for (i, p) in portals.iter().enumerate() {
        let [a, b] = p.leaves;
        if a == 0 || b == 0 || a > visleafs || b > visleafs || a == b {
            return Err(PrtError::Mismatch(format!(
                "portal {i} joins leaves {a} and {b}, not two of the visleafs 1..={visleafs}"
            )));
        }
        let pts = &p.winding.points;
        if pts.len() < 3 || pts.len() > MAX_POINTS {
            continue;
        }
        if !pts
            .iter()
            .all(|q| q.is_finite() && q.abs().max_element() <= MAX_COORD)
        {
            return Err(PrtError::Mismatch(format!(
                "portal {i} has a point that is not finite or out of range"
            )));
        }
        let newell = newell(pts);
        if newell.length() < 1e-9 {
            continue; // zero area: dropped on reading
        }
        let mut points: Vec<[f64; 3]> = pts.iter().map(|q| q.to_array()).collect();
        // Newell's normal points into the second leaf when read (see
        // `portals_for_level`): make it agree with the plane's, which points into
        // `leaves[1]`.
        if newell.dot(p.plane.normal) < 0.0 {
            points.reverse();
        }
        out.push(PrtPortal {
            points,
            leaves: [a - 1, b - 1],
        });
    }
    Ok(Prt {
        leaves: visleafs,
        portals: out,
    })
}

/// Newell's normal of a polygon (twice its area, along its normal).
fn newell(points: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for (k, a) in points.iter().enumerate() {
        n += a.cross(points[(k + 1) % points.len()]);
    }
    n
}

/// How far (Quake units) a portal point may lie outside the bounding boxes of its two
/// leaves (which the BSP stores rounded to integers) before the `.prt` is taken for
/// another level's.
pub const MATCH_TOLERANCE: f64 = 2.0;

/// The portals of `prt` as the solver's [`Portal`]s between BSP leaves, checked against
/// `level`: the leaf count must equal the level's visleafs, every portal must join two
/// open (not solid, not sky) leaves, and its points must lie within
/// [`MATCH_TOLERANCE`] of both leaves' boxes. A winding without a plane (all points on
/// a line) is dropped only if its area is zero, which no line can pass through.
pub fn portals_for_level(prt: &Prt, level: &BspLevel) -> Result<Vec<Portal>, PrtError> {
    if prt.leaves != level.visleafs {
        return Err(PrtError::Mismatch(format!(
            "the .prt has {} leaves, the level has {} visleafs",
            prt.leaves, level.visleafs
        )));
    }
    let mut out = Vec::with_capacity(prt.portals.len());
    for (i, p) in prt.portals.iter().enumerate() {
        let leaves = p.leaves.map(|k| k + 1);
        for l in leaves {
            let leaf = &level.leaves[l as usize];
            if !leaf.is_open() {
                return Err(PrtError::Mismatch(format!(
                    "portal {i} touches leaf {l}, which is solid or sky in the level"
                )));
            }
            let outside = p.points.iter().any(|q| {
                (0..3).any(|k| {
                    q[k] < leaf.mins[k] - MATCH_TOLERANCE || q[k] > leaf.maxs[k] + MATCH_TOLERANCE
                })
            });
            if outside {
                return Err(PrtError::Mismatch(format!(
                    "portal {i} lies outside the box of leaf {l}"
                )));
            }
        }
        let points: Vec<DVec3> = p.points.iter().map(|q| DVec3::from(*q)).collect();
        // vis's plane: (p0 - p1) × (p2 - p1) points into the first leaf. Newell's normal
        // (robust to collinear leading points) points the other way for the same order.
        let newell = newell(&points);
        let len = newell.length();
        if len < 1e-9 {
            continue; // zero area: no line passes through it
        }
        let normal = newell / len;
        let centre = points.iter().copied().sum::<DVec3>() / points.len() as f64;
        // Newell's normal points away from the first leaf, into the second.
        let plane = Plane::new(normal, normal.dot(centre));
        out.push(Portal {
            winding: Winding::new(points),
            plane,
            leaves,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str =
        "PRT1\n3\n2\n4 0 1 (0 0 0) (0 1 0) (0 1 1) (0 0 1)\n3 1 2 (1 0 0) (1 1 0) (1 1 1)\n";

    #[test]
    fn a_small_file_parses() {
        let p = parse_prt(GOOD.as_bytes()).unwrap();
        assert_eq!(p.leaves, 3);
        assert_eq!(p.portals.len(), 2);
        assert_eq!(p.portals[0].leaves, [0, 1]);
        assert_eq!(p.portals[1].points[2], [1.0, 1.0, 1.0]);
    }

    #[test]
    fn bad_files_are_one_line_errors() {
        let cases: &[(&str, &str)] = &[
            ("", "empty"),
            ("PRT2\n1\n1\n1\n", "PRT2"),
            ("HELLO\n", "expected PRT1"),
            ("PRT1\n", "leaf count"),
            ("PRT1\nx\n1\n", "not a number"),
            (
                "PRT1\n3\n2\n4 0 1 (0 0 0) (0 1 0) (0 1 1) (0 0 1)\n",
                "ends after 1 of 2",
            ),
            (
                "PRT1\n3\n1\n4 0 9 (0 0 0) (0 1 0) (0 1 1) (0 0 1)\n",
                "out of range",
            ),
            (
                "PRT1\n3\n1\n4 0 1 (0 0 0) (0 1 0) (0 1 1)\n",
                "point 4 of 4",
            ),
            (
                "PRT1\n3\n1\n3 0 1 (0 0 0) (0 1 0) (0 1 nan)\n",
                "not finite",
            ),
            ("PRT1\n3\n1\n2 0 1 (0 0 0) (0 1 0)\n", "2 points"),
            ("PRT1\n3\n1\n3 1 1 (0 0 0) (0 1 0) (0 1 1)\n", "itself"),
            (
                "PRT1\n3\n1\n3 0 1 (0 0 0) (0 1 0) (0 1 1) x\n",
                "after the 3 points",
            ),
            ("PRT1\n3\n4000000000\n", "cannot fit"),
            ("PRT1\n3\n0\nextra\n", "unexpected text"),
        ];
        for (text, want) in cases {
            let e = parse_prt(text.as_bytes()).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let e = parse_prt(&[b'P', 0xff, b'\n']).unwrap_err().to_string();
        assert!(e.contains("UTF-8"), "{e}");
    }
}

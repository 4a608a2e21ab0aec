//! Heights from tags and properties: `height`, `min_height`, `building:levels`,
//! `building:min_level`, with units (OSM conventions: "12", "12 m", "12.5m", "40 ft",
//! "40'", "12'6\"").

/// Metres per storey when only a number of levels is known.
pub const LEVEL_HEIGHT_M: f64 = 3.0;

/// Parse a length with an optional unit into metres. `None` if it is not a length.
pub fn parse_length(s: &str) -> Option<f64> {
    let s = s.trim();
    // Feet and inches: 12'6"
    if let Some((ft, rest)) = s.split_once('\'') {
        let ft: f64 = ft.trim().parse().ok()?;
        let inches = rest.trim().trim_end_matches('"').trim();
        let inches: f64 = if inches.is_empty() {
            0.0
        } else {
            inches.parse().ok()?
        };
        return Some(ft * 0.3048 + inches * 0.0254);
    }
    let num_end = s
        .find(|c: char| {
            !(c.is_ascii_digit() || c == '.' || c == ',' || c == '-' || c == '+' || c == 'e')
        })
        .unwrap_or(s.len());
    let (num, unit) = s.split_at(num_end);
    let num = num.trim().replace(',', ".");
    let v: f64 = num.parse().ok()?;
    let factor = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "m" | "meter" | "meters" | "metre" | "metres" => 1.0,
        "ft" | "feet" | "foot" => 0.3048,
        "cm" => 0.01,
        "km" => 1000.0,
        "mi" => 1609.344,
        _ => return None,
    };
    Some(v * factor)
}

/// A parsed numeric property.
#[derive(Debug, PartialEq)]
pub enum Num {
    Missing,
    Value(f64),
    /// Present but not a number: the original text, for the message.
    Invalid(String),
}

/// Interpret a JSON value as a length in metres.
pub fn json_length(v: Option<&serde_json::Value>) -> Num {
    match v {
        None | Some(serde_json::Value::Null) => Num::Missing,
        Some(serde_json::Value::Number(n)) => match n.as_f64() {
            Some(x) => Num::Value(x),
            None => Num::Invalid(n.to_string()),
        },
        Some(serde_json::Value::String(s)) => match parse_length(s) {
            Some(x) => Num::Value(x),
            None => Num::Invalid(format!("\"{s}\"")),
        },
        Some(other) => Num::Invalid(other.to_string()),
    }
}

/// Default height of a building without `height` or levels (a counted warning).
pub const DEFAULT_HEIGHT_M: f64 = 9.0;

/// What a feature becomes once its height properties are read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Extent {
    /// Lies on the ground (height 0, or a street).
    Flat,
    /// A prism from `base` to `top`.
    Prism { base: f64, top: f64 },
}

/// The height properties of one feature.
#[derive(Debug)]
pub struct HeightProps {
    pub height: Num,
    pub min_height: Num,
    pub levels: Num,
    pub min_level: Num,
}

/// Resolve the extent of a feature: `height` = top (0 → flat); else
/// `building:levels` × 3 m (warning `height-from-levels`); else [`DEFAULT_HEIGHT_M`]
/// (warning `height-default`). `min_height` = base, else `building:min_level` × 3 m,
/// else 0. Negative, non-finite or non-numeric heights and base ≥ top are errors.
pub fn resolve(
    p: &HeightProps,
    feature: usize,
    diag: &mut super::validate::Diagnostics,
) -> Result<Extent, String> {
    let top = match &p.height {
        Num::Value(h) if !h.is_finite() => return Err(format!("height {h} is not finite")),
        Num::Value(h) if *h < 0.0 => return Err(format!("negative height {h}")),
        Num::Value(h) if *h == 0.0 => return Ok(Extent::Flat),
        Num::Value(h) => *h,
        Num::Invalid(s) => return Err(format!("height {s} is not a number")),
        Num::Missing => match &p.levels {
            Num::Value(l) if l.is_finite() && *l > 0.0 => {
                diag.warn(
                    "height-from-levels",
                    Some(feature),
                    format!("no height: {l} levels x {LEVEL_HEIGHT_M} m"),
                );
                l * LEVEL_HEIGHT_M
            }
            other => {
                if !matches!(other, Num::Missing) {
                    diag.warn(
                        "invalid-levels",
                        Some(feature),
                        format!("building:levels {other:?} ignored"),
                    );
                }
                diag.warn(
                    "height-default",
                    Some(feature),
                    format!("no height: default {DEFAULT_HEIGHT_M} m"),
                );
                DEFAULT_HEIGHT_M
            }
        },
    };
    let base = match &p.min_height {
        Num::Value(b) if !b.is_finite() => return Err(format!("min_height {b} is not finite")),
        Num::Value(b) if *b < 0.0 => return Err(format!("negative min_height {b}")),
        Num::Value(b) => *b,
        Num::Invalid(s) => return Err(format!("min_height {s} is not a number")),
        Num::Missing => match &p.min_level {
            Num::Value(l) if l.is_finite() && *l >= 0.0 => l * LEVEL_HEIGHT_M,
            _ => 0.0,
        },
    };
    if base >= top {
        return Err(format!("min_height {base} is not below height {top}"));
    }
    Ok(Extent::Prism { base, top })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units() {
        assert_eq!(parse_length("12"), Some(12.0));
        assert_eq!(parse_length("12 m"), Some(12.0));
        assert_eq!(parse_length("12.5m"), Some(12.5));
        assert_eq!(parse_length("12,5"), Some(12.5));
        assert!((parse_length("40 ft").unwrap() - 12.192).abs() < 1e-9);
        assert!((parse_length("12'6\"").unwrap() - 3.81).abs() < 1e-9);
        assert_eq!(parse_length("tall"), None);
        assert_eq!(parse_length(""), None);
        assert_eq!(parse_length("12 parsecs"), None);
    }
}

//! PNG line charts for the report (plotters, bitmap backend).

use plotters::prelude::*;
use std::path::Path;

/// One named curve.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// Axis scaling of a chart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    Linear,
    Log,
}

/// The label of an axis tick: `1 200`-style integers, two significant digits below 10;
/// on a log axis only the ticks at 1, 2 and 5 × 10^k are labelled (the others crowd).
fn tick(v: f64, scale: Scale) -> String {
    if !v.is_finite() {
        return String::new();
    }
    if scale == Scale::Log && v > 0.0 {
        let m = v / 10f64.powf(v.log10().floor());
        if ![1.0, 2.0, 5.0, 10.0]
            .iter()
            .any(|k| (m - k).abs() < 1e-6 * k)
        {
            return String::new();
        }
    }
    if v == 0.0 {
        return "0".into();
    }
    if v.abs() >= 10.0 || (v.fract() == 0.0 && v.abs() >= 1.0) {
        let n = v.round() as i64;
        let digits = n.unsigned_abs().to_string();
        let mut out = String::new();
        for (i, c) in digits.chars().enumerate() {
            if i > 0 && (digits.len() - i).is_multiple_of(3) {
                out.push(' ');
            }
            out.push(c);
        }
        if n < 0 {
            out.insert(0, '-');
        }
        out
    } else {
        format!("{v:.2}")
    }
}

/// Draw `series` as lines with markers into a 900×560 PNG.
pub fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    x_scale: Scale,
    y_scale: Scale,
) -> anyhow::Result<()> {
    let pts = series.iter().flat_map(|s| s.points.iter()).filter(|p| {
        p.0.is_finite()
            && p.1.is_finite()
            && (x_scale == Scale::Linear || p.0 > 0.0)
            && (y_scale == Scale::Linear || p.1 > 0.0)
    });
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in pts {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.1);
        y1 = y1.max(p.1);
    }
    if x0 > x1 {
        anyhow::bail!("chart '{title}' has no finite points");
    }
    let pad = |a: f64, b: f64, s: Scale| -> (f64, f64) {
        match s {
            Scale::Log => (a / 1.3, b * 1.3),
            Scale::Linear => {
                let d = if b > a {
                    (b - a) * 0.08
                } else {
                    a.abs().max(1.0) * 0.1
                };
                (a - d, b + d)
            }
        }
    };
    let (x0, x1) = pad(x0, x1, x_scale);
    let (y0, y1) = pad(y0, y1, y_scale);
    let y0 = if y_scale == Scale::Linear && y0 < 0.0 && y1 > 0.0 && y0 > -0.05 * y1 {
        0.0
    } else {
        y0
    };

    let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    macro_rules! draw {
        ($xr:expr, $yr:expr) => {{
            let mut chart = ChartBuilder::on(&root)
                .caption(title, ("sans-serif", 22))
                .margin(14)
                .x_label_area_size(44)
                .y_label_area_size(64)
                .build_cartesian_2d($xr, $yr)?;
            let fx = |v: &f64| tick(*v, x_scale);
            let fy = |v: &f64| tick(*v, y_scale);
            chart
                .configure_mesh()
                .x_desc(x_label)
                .y_desc(y_label)
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .label_style(("sans-serif", 14))
                .draw()?;
            for (i, s) in series.iter().enumerate() {
                let color = Palette99::pick(i).to_rgba();
                let pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|p| p.0.is_finite() && p.1.is_finite())
                    .collect();
                chart
                    .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
                    .label(s.name.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                    });
                chart.draw_series(pts.iter().map(|p| Circle::new(*p, 4, color.filled())))?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .position(SeriesLabelPosition::UpperLeft)
                .draw()?;
        }};
    }
    match (x_scale, y_scale) {
        (Scale::Linear, Scale::Linear) => draw!(x0..x1, y0..y1),
        (Scale::Log, Scale::Linear) => draw!((x0..x1).log_scale(), y0..y1),
        (Scale::Linear, Scale::Log) => draw!(x0..x1, (y0..y1).log_scale()),
        (Scale::Log, Scale::Log) => draw!((x0..x1).log_scale(), (y0..y1).log_scale()),
    }
    root.present()?;
    Ok(())
}

/// Draw `series` as points into a 900×900 PNG with the same linear range on both axes
/// (from 0) and the line y = x, for comparing a size with a reference's.
pub fn scatter_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> anyhow::Result<()> {
    let max = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .fold(f64::NAN, |m, p| m.max(p.0).max(p.1));
    if max.is_nan() {
        anyhow::bail!("chart '{title}' has no finite points");
    }
    let top = max.max(1.0) * 1.05;
    let root = BitMapBackend::new(path, (900, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(0.0..top, 0.0..top)?;
    let fmt = |v: &f64| tick(*v, Scale::Linear);
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .label_style(("sans-serif", 14))
        .draw()?;
    chart
        .draw_series(LineSeries::new(
            vec![(0.0, 0.0), (top, top)],
            BLACK.stroke_width(1),
        ))?
        .label("y = x")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(1)));
    for (i, s) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        chart
            .draw_series(
                s.points
                    .iter()
                    .filter(|p| p.0.is_finite() && p.1.is_finite())
                    .map(|p| Circle::new(*p, 2, color.mix(0.6).filled())),
            )?
            .label(s.name.clone())
            .legend(move |(x, y)| Circle::new((x + 9, y), 4, color.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks() {
        assert_eq!(tick(10_000.0, Scale::Log), "10 000");
        assert_eq!(tick(9_000.0, Scale::Log), "");
        assert_eq!(tick(200.0, Scale::Log), "200");
        assert_eq!(tick(90.0, Scale::Log), "");
        assert_eq!(tick(0.5, Scale::Log), "0.50");
        assert_eq!(tick(2.0, Scale::Linear), "2");
        assert_eq!(tick(2.5, Scale::Linear), "2.50");
        assert_eq!(tick(150_000.0, Scale::Linear), "150 000");
        assert_eq!(tick(-12.0, Scale::Linear), "-12");
        assert_eq!(tick(0.0, Scale::Linear), "0");
    }

    #[test]
    fn draws_a_log_log_chart() {
        let dir = std::env::temp_dir().join(format!("sightline-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scaling.png");
        let series = vec![Series {
            name: "dual-ray".into(),
            points: vec![(1_000.0, 5.6), (10_000.0, 36.9), (150_000.0, 420.0)],
        }];
        line_chart(
            &path,
            "t",
            "buildings",
            "ms",
            &series,
            Scale::Log,
            Scale::Log,
        )
        .unwrap();
        let img = image::open(&path).unwrap();
        assert_eq!((img.width(), img.height()), (900, 560));
        assert!(line_chart(&path, "t", "x", "y", &[], Scale::Log, Scale::Log).is_err());
        let scatter = dir.join("scatter.png");
        let pts = vec![Series {
            name: "dm1".into(),
            points: vec![(10.0, 9.0), (120.0, 130.0)],
        }];
        scatter_chart(&scatter, "t", "vis", "ours", &pts).unwrap();
        let img = image::open(&scatter).unwrap();
        assert_eq!((img.width(), img.height()), (900, 900));
        assert!(scatter_chart(&scatter, "t", "x", "y", &[]).is_err());
        if std::env::var_os("SIGHTLINE_KEEP_PLOT").is_none() {
            std::fs::remove_dir_all(&dir).ok();
        }
    }
}

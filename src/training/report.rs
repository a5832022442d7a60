//! The session report: `report.json` (the summary first, then the goals, every figure and the history
//! sampled to a few hundred points, so it stays small), and a plot of stretch and completion over time
//! as a PNG (plotters, drawn into a buffer, encoded by `image`) drawn from the same report.

use std::path::Path;

use plotters::prelude::*;
#[cfg(not(target_arch = "wasm32"))]
use plotters::style::{FontStyle, register_font};
use thiserror::Error;

use serde::Serialize;

use super::{Assessment, Goals, Sample};

/// Why a report could not be written.
#[derive(Debug, Error)]
pub enum ReportError {
    /// Writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// Drawing or encoding the plot failed.
    #[error("{path}: could not draw the plot: {reason}")]
    Plot {
        /// The file.
        path: String,
        /// The cause.
        reason: String,
    },
}

/// Most history samples a report keeps.
pub const REPORT_SAMPLES: usize = 240;

/// What `report.json` holds, summary first.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct Report {
    /// The scene's title.
    pub title: String,
    /// When the report was written, UTC, `2026-11-24T02:10:33Z`.
    pub date: String,
    /// Whether the session passed the goals' pass mark.
    pub passed: bool,
    /// The score, 0 to 100.
    pub score: f32,
    /// The two things to improve most.
    pub feedback: Vec<String>,
    /// The exercise's goals.
    pub goals: Goals,
    /// Every figure.
    pub assessment: Assessment,
    /// Completion, stretch and force over time, at most [`REPORT_SAMPLES`] points; each keeps the
    /// highest stretch and force of the samples it stands for.
    pub history: Vec<Sample>,
}

/// At most `max` samples standing for `history`: consecutive runs merged, each keeping its last time
/// and completion and its highest stretch and force.
pub(crate) fn downsample(history: &[Sample], max: usize) -> Vec<Sample> {
    if history.len() <= max || max == 0 {
        return history.to_vec();
    }
    let per = history.len().div_ceil(max);
    history
        .chunks(per)
        .filter_map(|c| {
            let last = c.last()?;
            Some(Sample {
                stretch: c.iter().map(|s| s.stretch).fold(1.0, f32::max),
                force_n: c.iter().map(|s| s.force_n).fold(0.0, f32::max),
                ..*last
            })
        })
        .collect()
}

/// The UTC date and time of `secs` seconds since 1970 as `(year, month, day, hour, minute, second)`
/// (Howard Hinnant's civil-from-days algorithm).
pub fn utc_date_time(secs: u64) -> (i64, u32, u32, u32, u32, u32) {
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year, month, day, (rem / 3600) as u32, ((rem / 60) % 60) as u32, (rem % 60) as u32)
}

/// Now, UTC, as `2026-11-24T02:10:33Z` (the report's date).
pub fn utc_now_string() -> String {
    let secs =
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    let (y, mo, d, h, mi, s) = utc_date_time(secs);
    format!("{y:04}-{mo:02}-{d:02}T{h:02}:{mi:02}:{s:02}Z")
}

/// Writes `report.json`.
pub fn write_report(path: &Path, report: &Report) -> Result<(), ReportError> {
    let text = report_json(report)
        .map_err(|e| ReportError::Plot { path: path.display().to_string(), reason: e.to_string() })?;
    std::fs::write(path, text).map_err(|source| ReportError::Io { path: path.display().to_string(), source })
}

/// The text of `report.json` (the browser build offers it as a download).
pub fn report_json(report: &Report) -> Result<String, serde_json::Error> {
    serde_json::to_string_pretty(report)
}

/// Draws the report's stretch and completion over time, and below them the force on the instrument
/// against the goal's force limit, into a PNG of 800 x 700 pixels: the limits as dashed lines, the
/// stretch peak marked, the legend in a strip under the charts (never over the data).
pub fn write_plot(path: &Path, report: &Report) -> Result<(), ReportError> {
    let (w, h) = (800u32, 700u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let fail = |e: &dyn std::fmt::Display| ReportError::Plot {
        path: path.display().to_string(),
        reason: e.to_string(),
    };
    let history = &report.history;
    let a = &report.assessment;
    let limit = report.goals.stretch_limit;
    let limit_colour = RGBColor(90, 90, 90);
    let stretch_colour = RGBColor(200, 40, 40);
    let completion_colour = RGBColor(40, 80, 200);
    // egui's bundled font, so that the plot has text on a machine without system fonts.
    // (Natively only: plotters has no font registry on wasm, where the plot is not drawn.)
    #[cfg(not(target_arch = "wasm32"))]
    let _ = register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
    {
        let whole = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        whole.fill(&WHITE).map_err(|e| fail(&e))?;
        let (top, rest) = whole.split_vertically(450);
        let (below, legend) = rest.split_vertically(200);
        super::force::draw_force(&below, history, report.goals.force_limit, limit_colour)
            .map_err(|e| fail(&e))?;
        let t_max = history.last().map(|s| s.t).unwrap_or(1.0).max(0.01);
        let s_max = history.iter().map(|s| s.stretch).fold(limit.max(a.peak_stretch), f32::max);
        let s_min = 1.0f32;
        let s_top = s_min + (s_max - s_min) * 1.15 + 0.02;
        let verdict = if report.passed { "passed" } else { "not passed" };
        let caption = format!(
            "{}: score {:.0}, {verdict}; peak stretch {:.2} (limit {limit:.2})",
            report.title, a.score, a.peak_stretch
        );
        let layout = super::plot::Layout { caption: &caption, caption_size: 20, x_label_area: 36 };
        let mut chart = super::plot::time_chart(&top, &layout, t_max, s_min..s_top)
            .map_err(|e| fail(&e))?
            .set_secondary_coord(0f32..t_max, 0f32..100f32);
        super::plot::mesh(&mut chart, "peak stretch").map_err(|e| fail(&e))?;
        chart
            .configure_secondary_axes()
            .y_desc("completion (%)")
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| fail(&e))?;
        chart
            .draw_secondary_series(LineSeries::new(
                history.iter().map(|s| (s.t, 100.0 * s.completion)),
                completion_colour.stroke_width(2),
            ))
            .map_err(|e| fail(&e))?;
        super::plot::limit_and_line(
            &mut chart,
            t_max,
            (limit, limit_colour),
            history.iter().map(|s| (s.t, s.stretch)),
            stretch_colour,
        )
        .map_err(|e| fail(&e))?;
        if let Some(peak) = history.iter().max_by(|x, y| x.stretch.total_cmp(&y.stretch)) {
            chart
                .draw_series([Circle::new((peak.t, peak.stretch), 4, stretch_colour.filled())])
                .map_err(|e| fail(&e))?;
        }
        // The legend, in its own strip: the upper chart's line, then the force chart's.
        let entries: [(&str, RGBColor, bool, i32); 5] = [
            ("stretch (highest per sample)", stretch_colour, false, 0),
            ("stretch limit", limit_colour, true, 0),
            ("completion (right axis)", completion_colour, false, 0),
            ("force on the instrument (highest per sample)", super::force::FORCE_COLOUR, false, 1),
            ("force limit", limit_colour, true, 1),
        ];
        let (mut x, mut row) = (70, 0);
        for (label, colour, dashed, r) in entries {
            if r != row {
                (x, row) = (70, r);
            }
            let y = 16 + 22 * row;
            if dashed {
                for k in 0..3 {
                    legend
                        .draw(&PathElement::new(
                            vec![(x + k * 10, y), (x + k * 10 + 6, y)],
                            colour.stroke_width(2),
                        ))
                        .map_err(|e| fail(&e))?;
                }
            } else {
                legend
                    .draw(&PathElement::new(vec![(x, y), (x + 26, y)], colour.stroke_width(2)))
                    .map_err(|e| fail(&e))?;
            }
            legend
                .draw(&Text::new(label, (x + 34, y - 8), ("sans-serif", 15).into_font().color(&BLACK)))
                .map_err(|e| fail(&e))?;
            x += 40 + 8 * label.len() as i32;
        }
        whole.present().map_err(|e| fail(&e))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| fail(&"buffer size"))?;
    img.save(path).map_err(|e| fail(&e))
}

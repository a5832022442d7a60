//! The session report: `report.json` with every figure, and a plot of stretch and completion over time
//! as a PNG (plotters, drawn into a buffer, encoded by `image`).

use std::path::Path;

use plotters::prelude::*;
#[cfg(not(target_arch = "wasm32"))]
use plotters::style::{FontStyle, register_font};
use thiserror::Error;

use super::{Assessment, Sample};

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

/// Writes `report.json`: the assessment and its history.
pub fn write_report(path: &Path, assessment: &Assessment, history: &[Sample]) -> Result<(), ReportError> {
    let text = report_json(assessment, history)
        .map_err(|e| ReportError::Plot { path: path.display().to_string(), reason: e.to_string() })?;
    std::fs::write(path, text).map_err(|source| ReportError::Io { path: path.display().to_string(), source })
}

/// The text of `report.json` (the browser build offers it as a download).
pub fn report_json(assessment: &Assessment, history: &[Sample]) -> Result<String, serde_json::Error> {
    #[derive(serde::Serialize)]
    struct Report<'a> {
        assessment: &'a Assessment,
        history: &'a [Sample],
    }
    serde_json::to_string_pretty(&Report { assessment, history })
}

/// Draws stretch and completion over time, and below them the force on the instrument against
/// `force_limit` (newtons), into a PNG of 800 x 650 pixels.
pub fn write_plot(
    path: &Path,
    history: &[Sample],
    stretch_limit: f32,
    force_limit: f32,
) -> Result<(), ReportError> {
    let (w, h) = (800u32, 650u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let fail = |e: &dyn std::fmt::Display| ReportError::Plot {
        path: path.display().to_string(),
        reason: e.to_string(),
    };
    // egui's bundled font, so that the plot has text on a machine without system fonts.
    // (Natively only: plotters has no font registry on wasm, where the plot is not drawn.)
    #[cfg(not(target_arch = "wasm32"))]
    let _ = register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
    {
        let whole = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        whole.fill(&WHITE).map_err(|e| fail(&e))?;
        let (root, below) = whole.split_vertically(450);
        super::force::draw_force(&below, history, force_limit).map_err(|e| fail(&e))?;
        let t_max = history.last().map(|s| s.t).unwrap_or(1.0).max(0.01);
        let s_max = history.iter().map(|s| s.stretch).fold(stretch_limit, f32::max) * 1.1;
        let mut chart = ChartBuilder::on(&root)
            .caption("Stretch and completion over time", ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(50)
            .right_y_label_area_size(50)
            .build_cartesian_2d(0f32..t_max, 0f32..s_max)
            .map_err(|e| fail(&e))?
            .set_secondary_coord(0f32..t_max, 0f32..100f32);
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc("peak stretch")
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| fail(&e))?;
        chart
            .configure_secondary_axes()
            .y_desc("completion (%)")
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| fail(&e))?;
        chart
            .draw_series(LineSeries::new(history.iter().map(|s| (s.t, s.stretch)), RED.stroke_width(2)))
            .map_err(|e| fail(&e))?
            .label("stretch")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
        chart
            .draw_series(LineSeries::new([(0.0, stretch_limit), (t_max, stretch_limit)], BLACK.mix(0.4)))
            .map_err(|e| fail(&e))?
            .label("stretch limit")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.4)));
        chart
            .draw_secondary_series(LineSeries::new(
                history.iter().map(|s| (s.t, 100.0 * s.completion)),
                BLUE.stroke_width(2),
            ))
            .map_err(|e| fail(&e))?
            .label("completion")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(|e| fail(&e))?;
        whole.present().map_err(|e| fail(&e))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| fail(&"buffer size"))?;
    img.save(path).map_err(|e| fail(&e))
}

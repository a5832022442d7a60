//! The charts of `report.png`, one way for both: time on x (seconds since the first instrument
//! action), a figure on y, its limit dashed across and its history as a line.
//!
//! Must not import wgpu, winit or egui.

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf32;
use plotters::prelude::*;

/// A chart over time.
pub(crate) type TimeChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf32, RangedCoordf32>>;

/// A plotting error as text.
pub(crate) fn fail(e: &dyn std::fmt::Display) -> String {
    e.to_string()
}

/// How a chart over time is laid out.
pub(crate) struct Layout<'a> {
    /// Caption over the chart.
    pub caption: &'a str,
    /// The caption's font size.
    pub caption_size: u32,
    /// Height of the time axis' label area, pixels.
    pub x_label_area: u32,
}

/// A chart of a figure in `y` over `0..t_max` seconds on `area`, with its caption (room is left for
/// a right-hand axis). Its mesh is drawn by [`mesh`], once any secondary axis is set.
pub(crate) fn time_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    layout: &Layout,
    t_max: f32,
    y: Range<f32>,
) -> Result<TimeChart<'a, DB>, String> {
    ChartBuilder::on(area)
        .caption(layout.caption, ("sans-serif", layout.caption_size))
        .margin(12)
        .x_label_area_size(layout.x_label_area)
        .y_label_area_size(50)
        .right_y_label_area_size(50)
        .build_cartesian_2d(0f32..t_max, y)
        .map_err(|e| fail(&e))
}

/// The chart's mesh: time along x, `y_desc` up the y axis.
pub(crate) fn mesh<DB: DrawingBackend>(chart: &mut TimeChart<'_, DB>, y_desc: &str) -> Result<(), String> {
    chart
        .configure_mesh()
        .x_desc("time since the first instrument action (s)")
        .y_desc(y_desc)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| fail(&e))
}

/// The limit, dashed across the chart, then the figure's history as a line.
pub(crate) fn limit_and_line<DB: DrawingBackend>(
    chart: &mut TimeChart<'_, DB>,
    t_max: f32,
    limit: (f32, RGBColor),
    points: impl Iterator<Item = (f32, f32)>,
    colour: RGBColor,
) -> Result<(), String> {
    chart
        .draw_series(DashedLineSeries::new([(0.0, limit.0), (t_max, limit.0)], 8, 5, limit.1.stroke_width(2)))
        .map_err(|e| fail(&e))?;
    chart.draw_series(LineSeries::new(points, colour.stroke_width(2))).map_err(|e| fail(&e))?;
    Ok(())
}

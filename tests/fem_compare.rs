//! Guards `dissect::fem::compare`: on a small block it runs, ChainMail reaches the imposed displacement,
//! relaxation converges, the errors are finite and the table prints. Prints the report with
//! `--nocapture`.

use dissect::fem::{CompareConfig, FemError, compare};

#[test]
fn compare_runs_on_block_8() {
    let cfg = CompareConfig { dims: [8, 8, 8], timing_repeats: 3, ..CompareConfig::default() };
    let report = compare(&cfg).expect("compare");
    println!("{report}");
    assert_eq!(report.rows.len(), 2);
    assert_eq!(report.surface_nodes, 8 * 8 * 8 - 6 * 6 * 6 - 64);
    for row in &report.rows {
        assert_eq!(row.chainmail_achieved, 1.0, "{row:?}");
        assert!(row.converged, "{row:?}");
        for x in [row.rms_unrelaxed, row.rms_step, row.rms_relaxed, row.max_relaxed] {
            assert!(x.is_finite() && x >= 0.0, "{row:?}");
        }
        assert!(row.fem_step_us > 0.0 && row.chainmail_step_us > 0.0);
        assert!(row.fem_force[1] < 0.0, "pushing down: {:?}", row.fem_force);
    }
    let text = report.to_string();
    assert!(text.contains("rms relaxed") && text.contains("20 %"), "{text}");
    assert!(serde_json::to_string(&report).is_ok_and(|s| s.contains("rms_relaxed")));
}

#[test]
fn compare_refuses_bad_config() {
    let bad = CompareConfig { direction: [0.0; 3], ..CompareConfig::default() };
    assert!(matches!(compare(&bad), Err(FemError::BadParameter(_))));
    let bad = CompareConfig { magnitudes: vec![f64::NAN], ..CompareConfig::default() };
    assert!(matches!(compare(&bad), Err(FemError::BadParameter(_))));
    let bad = CompareConfig { dims: [0, 8, 8], ..CompareConfig::default() };
    assert!(matches!(compare(&bad), Err(FemError::EmptyGrid { .. })));
}

/// The full-size comparison (block_16); slow in debug. Run with
/// `cargo test --release --test fem_compare -- --ignored --nocapture`.
#[test]
#[ignore]
fn compare_block_16() {
    let report = compare(&CompareConfig::default()).expect("compare");
    println!("{report}");
    println!("{}", serde_json::to_string_pretty(&report.rows).unwrap_or_default());
}

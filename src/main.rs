//! The `dissect` command line: open the trainer, check scenes, run a script headless, replay a
//! recording, compare runs. The only place that uses `anyhow`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use dissect::runner;
use dissect::scene::{Scene, Script};

/// A soft-tissue cutting trainer: layers of tissue cut apart and pulled away in real time.
#[derive(Parser, Debug)]
#[command(
    name = "dissect",
    version,
    about,
    after_help = "Examples:\n  dissect                                 open the trainer with the default scene\n  dissect scenes/cylinder.ron --single-window   both views in one window; the file is hot-reloaded\n  dissect check scenes/*.ron              check scene files\n  dissect run scenes/meninges.ron --script scenes/scripts/meninges.ron --out out/\n  dissect replay out/recording.ron\n\nScene and script formats: scenes/README.md"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// The scene to open (RON); default: the built-in dural incision and reflection exercise. A scene file is watched and
    /// reloaded when it changes.
    #[arg(value_name = "SCENE")]
    scene: Option<PathBuf>,
    #[command(flatten)]
    window: WindowArgs,
    /// Play a script (or recording) instead of taking input, on SCENE (for demonstrations).
    #[arg(long, value_name = "SCRIPT", hide = true)]
    demo_script: Option<PathBuf>,
}

/// Options of the trainer's windows.
#[derive(clap::Args, Debug, Clone)]
struct WindowArgs {
    /// Show the trainee's and the observers' views side by side in one window.
    #[arg(long)]
    single_window: bool,
    /// Exit after N frames (for smoke tests).
    #[arg(long, value_name = "N")]
    frames: Option<u64>,
    /// Record the session here (default: recordings/<date>_<time>.ron).
    #[arg(long, value_name = "PATH")]
    record: Option<PathBuf>,
    /// Where screenshots (F12 / P) go (default: screenshots/).
    #[arg(long, value_name = "DIR")]
    screenshot_dir: Option<PathBuf>,
    /// The haptic device: `mouse` (default) or `inverse3` (a Haply Inverse3, built with the `haply`
    /// feature). With no device found the trainer says so and uses the mouse.
    #[arg(long, value_name = "DEVICE", default_value = "mouse")]
    haptic: String,
    /// Educator mode: the material and simulation panels in the trainee's window (without it a trainee
    /// cannot change the tissue or the solver mid-assessment).
    #[arg(long)]
    educator: bool,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Check scene files: print `ok: PATH` for each valid one, or `PATH:LINE:COLUMN: what is wrong`.
    #[command(
        after_help = "Exit status: 0 when every scene is valid, 1 otherwise.\n\nExample:\n  dissect check scenes/meninges.ron scenes/cylinder.ron"
    )]
    Check {
        /// Scene files (RON) to check.
        #[arg(required = true, value_name = "SCENE")]
        scenes: Vec<PathBuf>,
        /// Treat the files as scripts instead of scenes.
        #[arg(long)]
        script: bool,
    },
    /// Run a scene headless, driven by a script, and write what happened to a directory.
    #[command(
        after_help = "Example:\n  dissect run scenes/meninges.ron --script scenes/scripts/meninges.ron --out out/meninges --steps 3000"
    )]
    Run {
        /// The scene file (RON).
        #[arg(value_name = "SCENE")]
        scene: PathBuf,
        /// The script of instrument actions (RON).
        #[arg(long, value_name = "SCRIPT")]
        script: PathBuf,
        /// Directory the results are written to (created if missing).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Steps to simulate, at most until the script ends (and at most 10 000 000). Default: until
        /// the script ends.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=dissect::scene::MAX_SCRIPT_STEPS))]
        steps: Option<u64>,
        /// Also record the session's input to this file (a recording, replayable and usable as a
        /// script).
        #[arg(long, value_name = "FILE")]
        record: Option<PathBuf>,
    },
    /// Replay a recorded session in the trainer's windows (input disabled, cameras free).
    #[command(after_help = "Example:\n  dissect replay recordings/2026-11-22_10-00-00.ron")]
    Replay {
        /// The recording file.
        #[arg(value_name = "FILE")]
        file: PathBuf,
        #[command(flatten)]
        window: WindowArgs,
    },
    /// Compare ChainMail with the linear finite-element reference on the same block: surface
    /// displacement error (RMS, relative to the imposed displacement) and time per step of each.
    #[command(
        after_help = "The block has N x N x N nodes 5 mm apart, its base clamped; the top nodes within the grasp radius of\nthe top centre are pushed down together by 2% and by 20% of the block's height.\n\nExample:\n  dissect compare --nodes 16 --json out/compare.json\n  dissect compare --nodes 16 --grasp-radius 0 --limits 1.2,0.7,0.3\n  dissect compare --nodes 16 --energy links   # Gibson's relaxation of the links' springs"
    )]
    Compare {
        /// Nodes along each axis of the block (2 to 256; the model refuses more than 512 MiB of matrices).
        #[arg(long, value_name = "N", default_value_t = 16, value_parser = clap::value_parser!(u16).range(2..=256))]
        nodes: u16,
        /// Top nodes within this distance of the top centre are grasped, metres (0: one node).
        #[arg(long, value_name = "M", default_value_t = 0.005)]
        grasp_radius: f64,
        /// ChainMail's relative limits: stretch, compress, shear.
        #[arg(long, value_name = "S,C,SH", value_delimiter = ',', default_values_t = [1.2, 0.7, 0.3])]
        limits: Vec<f32>,
        /// What ChainMail's relaxation lowers: `cells`, the linear-elastic energy of each lattice cell
        /// with the FEM material's Poisson's ratio; `links`, each link a spring on its offset
        /// (Gibson's relaxation, no Poisson effect).
        #[arg(long, value_name = "ENERGY", default_value = "cells")]
        energy: Energy,
        /// Also write the report as JSON.
        #[arg(long, value_name = "FILE")]
        json: Option<PathBuf>,
    },
}

/// What the compared ChainMail's relaxation lowers.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Energy {
    /// The linear-elastic energy of each lattice cell, with the FEM material's Poisson's ratio.
    Cells,
    /// Each link a spring on its offset (Gibson's relaxation).
    Links,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        None => {
            let source = match cli.demo_script {
                Some(script) => dissect::app::Source::Demo(script),
                None => dissect::app::Source::Live,
            };
            let mut inputs: Vec<&Path> = cli.scene.iter().map(PathBuf::as_path).collect();
            if let dissect::app::Source::Demo(script) = &source {
                inputs.push(script);
            }
            if let Err(e) = record_apart(cli.window.record.as_deref(), &inputs) {
                eprintln!("{e}");
                return Ok(ExitCode::FAILURE);
            }
            open_app(cli.scene, cli.window, source)
        }
        Some(Command::Check { scenes, script }) => Ok(check(&scenes, script)),
        Some(Command::Run { scene, script, out, steps, record }) => {
            run_headless(&scene, &script, &out, steps, record.as_deref())
        }
        Some(Command::Replay { file, window }) => {
            if let Err(e) = record_apart(window.record.as_deref(), &[&file]) {
                eprintln!("{e}");
                return Ok(ExitCode::FAILURE);
            }
            open_app(None, window, dissect::app::Source::Replay(file))
        }
        Some(Command::Compare { nodes, grasp_radius, limits, energy, json }) => {
            let n = usize::from(nodes);
            let &[stretch, compress, shear] = limits.as_slice() else {
                eprintln!("dissect compare: --limits takes three numbers: stretch,compress,shear");
                return Ok(ExitCode::FAILURE);
            };
            let base = dissect::fem::CompareConfig::default();
            let poisson_ratio = match energy {
                Energy::Cells => Some(base.material.poisson as f32),
                Energy::Links => None,
            };
            let cfg = dissect::fem::CompareConfig {
                dims: [n; 3],
                grasp_radius,
                chainmail: dissect::chainmail::Material {
                    poisson_ratio,
                    young_modulus: base.material.young as f32,
                    ..dissect::chainmail::Material::relative(stretch, compress, shear)
                },
                ..base
            };
            if let Some(path) = &json
                && let Err(e) = writable_file(path)
            {
                eprintln!("{e}");
                return Ok(ExitCode::FAILURE);
            }
            match dissect::fem::compare(&cfg) {
                Ok(report) => {
                    say(format_args!("{report}"));
                    if let Some(path) = json {
                        std::fs::write(&path, serde_json::to_string_pretty(&report)?)
                            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
                    }
                    Ok(ExitCode::SUCCESS)
                }
                Err(e) => {
                    eprintln!("dissect compare: {e}");
                    Ok(ExitCode::FAILURE)
                }
            }
        }
    }
}

/// Opens the trainer's windows.
fn open_app(
    scene: Option<PathBuf>,
    window: WindowArgs,
    source: dissect::app::Source,
) -> anyhow::Result<ExitCode> {
    let options = dissect::app::AppOptions {
        scene,
        single_window: window.single_window,
        frames: window.frames,
        record: window.record,
        screenshot_dir: window.screenshot_dir,
        source,
        haptic: window.haptic,
        educator: window.educator,
    };
    match dissect::app::run(options) {
        Ok(()) => Ok(ExitCode::SUCCESS),
        Err(e) => {
            eprintln!("dissect: {e}");
            Ok(ExitCode::FAILURE)
        }
    }
}

/// `dissect run`: the scene driven by the script, without a window; results into `out`.
fn run_headless(
    scene_path: &Path,
    script_path: &Path,
    out: &Path,
    steps: Option<u64>,
    record: Option<&Path>,
) -> anyhow::Result<ExitCode> {
    let (scene, source) = match Scene::load_with_source(scene_path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return Ok(ExitCode::FAILURE);
        }
    };
    let script = match Script::load(script_path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return Ok(ExitCode::FAILURE);
        }
    };
    // Everything that is written is checked before the simulation starts: a run can be long.
    if let Err(e) = record_apart(record, &[scene_path, script_path]).and_then(|()| writable_dir(out)) {
        eprintln!("{e}");
        return Ok(ExitCode::FAILURE);
    }
    // `--steps` never runs past the script's end.
    let steps = steps.map(|n| n.min(script.duration_steps()));
    let recorder = match record {
        Some(path) => {
            match dissect::scene::Recorder::create(path, &scene_path.display().to_string(), &source) {
                Ok(r) => Some(r),
                Err(e) => {
                    eprintln!("{}: cannot write the recording: {e}", path.display());
                    return Ok(ExitCode::FAILURE);
                }
            }
        }
        None => None,
    };
    // Stepped as the trainer's simulation thread steps: a worker of a pool of its own, so that a step
    // never waits for a helper thread without a core (`chainmail::worker_pool`). Without one, rayon's
    // global pool; the states are the same either way.
    let _pool = dissect::chainmail::worker_pool("dissect-run").ok();
    let mut result = runner::run(
        &scene,
        &scene_path.display().to_string(),
        &script,
        &script_path.display().to_string(),
        steps,
        recorder,
    )
    .and_then(|output| runner::write_outputs(out, &output).map(|()| output));
    if let Ok(output) = &mut result
        && let Some(r) = output.recorder.take()
        && let Err(e) = r.finish(output.world.step_count())
    {
        eprintln!("cannot finish the recording: {e}");
        return Ok(ExitCode::FAILURE);
    }
    match result {
        Ok(output) => {
            if let Err(e) = write_pictures(&scene, &output.world, out) {
                eprintln!("{e}");
                return Ok(ExitCode::FAILURE);
            }
            let m = &output.metrics;
            say(format_args!(
                "{} steps, {} elements moved, {} links cut, {} torn, step time mean {:.1} us (p99 {:.1} us); results in {}",
                m.steps,
                m.elements_moved_total,
                m.links_cut,
                m.links_torn,
                m.step_time_us.mean,
                m.step_time_us.p99,
                out.display()
            ));
            if let Some(a) = &m.assessment {
                say(format_args!("score {:.1}: completion {:.0}%", a.score, 100.0 * a.completion));
            }
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => {
            eprintln!("{e}");
            Ok(ExitCode::FAILURE)
        }
    }
}

/// Renders the final state from the trainee's and the observer's cameras into `trainee.png` and
/// `observer.png`, offscreen.
fn write_pictures(scene: &Scene, world: &dissect::simulation::World, out: &Path) -> anyhow::Result<()> {
    use dissect::render::{Gpu, OrbitCamera, render_to_image, save_png};
    let gpu = Gpu::headless().map_err(|e| anyhow::anyhow!("cannot render the pictures: {e}"))?;
    let mut snapshot = dissect::simulation::Snapshot::default();
    world.snapshot_into(&mut snapshot);
    for (name, camera) in [("trainee", scene.trainee_camera()), ("observer", scene.observer_camera())] {
        let image = render_to_image(&gpu, &snapshot, &OrbitCamera::from_spec(&camera), 1280, 800)
            .map_err(|e| anyhow::anyhow!("cannot render {name}.png: {e}"))?;
        let path = out.join(format!("{name}.png"));
        save_png(&image, &path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    Ok(())
}

/// Checks every file, reporting each; failure if any is invalid. A scene whose steps will cost far
/// more than its rate allows gets a warning (it is still valid). When nobody reads the output any more
/// (a closed pipe), the check ends quietly.
fn check(paths: &[PathBuf], scripts: bool) -> ExitCode {
    let mut ok = true;
    for path in paths {
        let result = if scripts {
            Script::check_file(path)
        } else {
            Scene::load(path).map(|scene| {
                if let Some(w) = scene.cost_warning() {
                    eprintln!("{}: warning: {w}", path.display());
                }
            })
        };
        match result {
            Ok(()) => {
                if !say(format_args!("ok: {}", path.display())) {
                    break;
                }
            }
            Err(e) => {
                ok = false;
                eprintln!("{e}");
            }
        }
    }
    if ok { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}

/// Prints a line on the standard output; false when it cannot be written (a reader that went away:
/// `dissect check *.ron | head -1`), which the caller takes as a reason to stop, not to panic.
fn say(line: std::fmt::Arguments) -> bool {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{line}").and_then(|()| out.flush()).is_ok()
}

/// Refuses a recording path that is one of the inputs (the same file under any name): recording
/// would overwrite it.
fn record_apart(record: Option<&Path>, inputs: &[&Path]) -> anyhow::Result<()> {
    let Some(record) = record else { return Ok(()) };
    for input in inputs {
        if same_file::is_same_file(record, input).unwrap_or(false) {
            anyhow::bail!(
                "{}: --record would overwrite an input file ({}); expected a new file for the recording",
                record.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// Makes sure the output directory exists (created if missing) and takes files, before anything is
/// simulated.
fn writable_dir(dir: &Path) -> anyhow::Result<()> {
    if dir.exists() && !dir.is_dir() {
        anyhow::bail!(
            "{}: is not a directory, expected a directory for the results (--out DIR)",
            dir.display()
        );
    }
    std::fs::create_dir_all(dir)
        .map_err(|e| anyhow::anyhow!("{}: cannot create the output directory: {e}", dir.display()))?;
    let probe = dir.join(format!(".dissect-write-check-{}", std::process::id()));
    std::fs::File::create(&probe)
        .map_err(|e| anyhow::anyhow!("{}: cannot write in the output directory: {e}", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    for name in ["metrics.json", "state.json", "report.json", "report.png", "trainee.png", "observer.png"] {
        if dir.join(name).is_dir() {
            anyhow::bail!("{}: is a directory, expected room for a file", dir.join(name).display());
        }
    }
    Ok(())
}

/// Makes sure a file can be written (its directory exists and it is not a directory), without
/// changing it.
fn writable_file(path: &Path) -> anyhow::Result<()> {
    if path.is_dir() {
        anyhow::bail!("{}: is a directory, expected a file name", path.display());
    }
    std::fs::OpenOptions::new()
        .append(true)
        .create(true)
        .open(path)
        .map(drop)
        .map_err(|e| anyhow::anyhow!("{}: cannot write the file: {e}", path.display()))
}

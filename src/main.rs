//! The `dissect` command line: open the trainer, check scenes, run a script headless, replay a
//! recording, compare runs. The only place that uses `anyhow`.

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
    /// Educator mode: show the material and simulation panels in the trainee's window (without it a
    /// trainee cannot change the tissue mid-assessment).
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
        /// Steps to simulate. Default: until the script ends.
        #[arg(long, value_name = "N")]
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
        after_help = "The block has N x N x N nodes 5 mm apart, its base clamped; its top-centre node is pushed down by\n2% and by 20% of the block's height.\n\nExample:\n  dissect compare --nodes 16 --json out/compare.json"
    )]
    Compare {
        /// Nodes along each axis of the block.
        #[arg(long, value_name = "N", default_value_t = 16)]
        nodes: usize,
        /// Also write the report as JSON.
        #[arg(long, value_name = "FILE")]
        json: Option<PathBuf>,
    },
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
            open_app(cli.scene, cli.window, source)
        }
        Some(Command::Check { scenes, script }) => Ok(check(&scenes, script)),
        Some(Command::Run { scene, script, out, steps, record }) => {
            run_headless(&scene, &script, &out, steps, record.as_deref())
        }
        Some(Command::Replay { file, window }) => open_app(None, window, dissect::app::Source::Replay(file)),
        Some(Command::Compare { nodes, json }) => {
            let cfg = dissect::fem::CompareConfig { dims: [nodes; 3], ..Default::default() };
            match dissect::fem::compare(&cfg) {
                Ok(report) => {
                    println!("{report}");
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
    let scene = match Scene::load(scene_path) {
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
    let mut recorder = match record {
        Some(path) => {
            let source = std::fs::read_to_string(scene_path).unwrap_or_default();
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
    let result = runner::run(
        &scene,
        &scene_path.display().to_string(),
        &script,
        &script_path.display().to_string(),
        steps,
        recorder.as_mut(),
    )
    .and_then(|output| runner::write_outputs(out, &output).map(|()| output));
    if let (Some(r), Ok(output)) = (recorder, &result)
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
            println!(
                "{} steps, {} elements moved, {} links cut, {} torn, step time mean {:.1} us (p99 {:.1} us); results in {}",
                m.steps,
                m.elements_moved_total,
                m.links_cut,
                m.links_torn,
                m.step_time_us.mean,
                m.step_time_us.p99,
                out.display()
            );
            if let Some(a) = &m.assessment {
                println!("score {:.1}: completion {:.0}%", a.score, 100.0 * a.completion);
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

/// Checks every file, reporting each; failure if any is invalid.
fn check(paths: &[PathBuf], scripts: bool) -> ExitCode {
    let mut ok = true;
    for path in paths {
        let result = if scripts { Script::load(path).map(|_| ()) } else { Scene::load(path).map(|_| ()) };
        match result {
            Ok(()) => println!("ok: {}", path.display()),
            Err(e) => {
                ok = false;
                eprintln!("{e}");
            }
        }
    }
    if ok { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}

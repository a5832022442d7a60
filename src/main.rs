//! The `dissect` command line: open the trainer, check scenes, run a script headless, replay a
//! recording, compare runs. The only place that uses `anyhow`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use dissect::scene::{Scene, Script};

/// A soft-tissue cutting trainer: layers of tissue cut apart and pulled away in real time.
#[derive(Parser, Debug)]
#[command(
    name = "dissect",
    version,
    about,
    after_help = "Examples:\n  dissect                                 open the trainer with the default scene\n  dissect check scenes/*.ron              check scene files\n  dissect run scenes/meninges.ron --script scenes/scripts/meninges.ron --out out/\n  dissect replay out/recording.ron\n\nScene and script formats: scenes/README.md"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
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
    },
    /// Replay a recorded session.
    #[command(after_help = "Example:\n  dissect replay out/meninges/recording.ron")]
    Replay {
        /// The recording file.
        #[arg(value_name = "FILE")]
        file: PathBuf,
    },
    /// Compare two runs or recordings.
    #[command(after_help = "Example:\n  dissect compare out/a out/b")]
    Compare {
        /// Runs or recordings to compare.
        #[arg(value_name = "RUN")]
        runs: Vec<PathBuf>,
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
            println!(
                "dissect: the trainer window is not wired yet; try `dissect check scenes/meninges.ron`."
            );
            Ok(ExitCode::SUCCESS)
        }
        Some(Command::Check { scenes, script }) => Ok(check(&scenes, script)),
        Some(Command::Run { scene, script, out, steps }) => {
            let _ = (scene, script, out, steps);
            println!("dissect run: not yet wired");
            Ok(ExitCode::SUCCESS)
        }
        Some(Command::Replay { file }) => {
            let _ = file;
            println!("dissect replay: not yet wired");
            Ok(ExitCode::SUCCESS)
        }
        Some(Command::Compare { runs }) => {
            let _ = runs;
            println!("dissect compare: not yet wired");
            Ok(ExitCode::SUCCESS)
        }
    }
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

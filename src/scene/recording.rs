//! Recordings: a session's input stream, timestamped in steps, written as it happens so that a crash
//! loses at most the last second. A recording is a script (`At(step)` and raw `Command(..)` actions)
//! with the scene it was made on, so `dissect replay FILE` needs nothing else and `dissect run SCENE
//! --script FILE` accepts it as a script.
//!
//! ```ron
//! Recording(
//!     scene: "scenes/meninges.ron",
//!     scene_source: "Scene(...)",
//!     actions: [
//!         At(0), Command(Select(Forceps)),
//!         At(12), Command(MoveTo((0.0, 0.01, 0.0))),
//!     ],
//! )
//! ```

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use web_time::Instant;

use serde::{Deserialize, Serialize};

use super::error::{FieldPath, parse_error};
use super::{Action, SceneError, Script};
use crate::simulation::Command;

/// How often a recording reaches the disk.
pub const FLUSH_EVERY: Duration = Duration::from_secs(1);

/// A recorded session.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Recording {
    /// Path of the scene as it was opened (for people).
    pub scene: String,
    /// The scene's text when the session started (what replay builds).
    pub scene_source: String,
    /// The input stream: `At(step)` followed by the commands given before that step.
    pub actions: Vec<Action>,
}

/// Whether a text is a recording rather than a plain script.
pub(crate) fn is_recording(src: &str) -> bool {
    src.lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with("//"))
        .is_some_and(|l| l.starts_with("Recording("))
}

/// Whether a line of the action list holds whole actions: every bracket it opens closed (outside
/// strings), and a comma after the last. A line cut after a comma inside a tuple does not.
fn complete(line: &str) -> bool {
    let mut depth = 0i64;
    let mut in_string = false;
    let mut escaped = false;
    for c in line.chars() {
        if in_string {
            match (escaped, c) {
                (true, _) => escaped = false,
                (false, '\\') => escaped = true,
                (false, '"') => in_string = false,
                _ => {}
            }
            continue;
        }
        match c {
            '"' => in_string = true,
            '(' | '[' | '{' => depth += 1,
            ')' | ']' | '}' => depth -= 1,
            _ => {}
        }
        if depth < 0 {
            return false;
        }
    }
    depth == 0 && !in_string && line.trim_end().ends_with(',')
}

/// A recording cut short by a crash ends inside its action list: keep every complete action line and
/// close the list.
fn repaired(src: &str) -> String {
    let mut out = String::with_capacity(src.len() + 16);
    let mut in_actions = false;
    for line in src.lines() {
        if in_actions {
            let t = line.trim();
            if t.starts_with(']') {
                // The list is complete and the file is cut after it: close it as the recorder does.
                break;
            }
            if !complete(t) {
                break;
            }
        } else if line.trim_start().starts_with("actions:") {
            in_actions = true;
        }
        out.push_str(line);
        out.push('\n');
    }
    if in_actions {
        out.push_str("    ],\n)\n");
    }
    out
}

impl Recording {
    /// Reads a recording, repairing one that a crash cut short.
    pub fn load(path: impl AsRef<Path>) -> Result<Recording, SceneError> {
        let path = path.as_ref();
        Self::from_str(&super::read(path)?, path)
    }

    /// Parses a recording from text (repairing a cut-off tail); `path` is for messages.
    pub fn from_str(src: &str, path: impl AsRef<Path>) -> Result<Recording, SceneError> {
        Self::parse(src, path.as_ref()).map(|(rec, _)| rec)
    }

    /// Parses and checks a recording; also gives the text it was read from (repaired when cut off), in
    /// which errors about it are located.
    pub(crate) fn parse(src: &str, path: &Path) -> Result<(Recording, String), SceneError> {
        let parsed = super::ron_options().from_str::<Recording>(src);
        let (rec, text) = match parsed {
            Ok(r) => (r, src.to_owned()),
            Err(e) => {
                let fixed = repaired(src);
                match super::ron_options().from_str::<Recording>(&fixed) {
                    Ok(r) => (r, fixed),
                    Err(_) => return Err(parse_error(path, src, &e)),
                }
            }
        };
        rec.script().check(&FieldPath::default().f("actions")).map_err(|p| p.into_error(path, &text))?;
        Ok((rec, text))
    }

    /// The recorded actions as a script.
    pub fn script(&self) -> Script {
        Script(self.actions.clone())
    }
}

/// Writes a recording as the session goes.
pub struct Recorder {
    out: BufWriter<File>,
    path: PathBuf,
    last_flush: Instant,
    last_step: Option<u64>,
}

impl Recorder {
    /// Starts a recording of a session on the scene at `scene_path` whose text is `scene_source`.
    pub fn create(path: impl AsRef<Path>, scene_path: &str, scene_source: &str) -> std::io::Result<Self> {
        let path = path.as_ref().to_path_buf();
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        let mut out = BufWriter::new(File::create(&path)?);
        let quote = |s: &str| ron::to_string(s).map_err(std::io::Error::other);
        writeln!(out, "// dissect recording: replay with `dissect replay {}`", path.display())?;
        writeln!(out, "Recording(")?;
        writeln!(out, "    scene: {},", quote(scene_path)?)?;
        writeln!(out, "    scene_source: {},", quote(scene_source)?)?;
        writeln!(out, "    actions: [")?;
        out.flush()?;
        Ok(Self { out, path, last_flush: Instant::now(), last_step: None })
    }

    /// Where the recording goes.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Records a command given before step `step` (the world's step count when it was queued).
    pub fn record(&mut self, step: u64, command: &Command) -> std::io::Result<()> {
        let c = ron::to_string(&Action::Command(command.clone())).map_err(std::io::Error::other)?;
        if self.last_step != Some(step) {
            writeln!(self.out, "        At({step}), {c},")?;
            self.last_step = Some(step);
        } else {
            writeln!(self.out, "        {c},")?;
        }
        if self.last_flush.elapsed() >= FLUSH_EVERY {
            self.flush()?;
        }
        Ok(())
    }

    /// Records where the trainee's camera looks from step `step` on (a `View` action: nothing for the
    /// world, the replay's camera).
    pub fn record_view(&mut self, step: u64, camera: &crate::snapshot::CameraSpec) -> std::io::Result<()> {
        let v = ron::to_string(&Action::View(*camera)).map_err(std::io::Error::other)?;
        if self.last_step != Some(step) {
            writeln!(self.out, "        At({step}), {v},")?;
            self.last_step = Some(step);
        } else {
            writeln!(self.out, "        {v},")?;
        }
        Ok(())
    }

    /// Pushes what is buffered to the disk.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.last_flush = Instant::now();
        self.out.flush()
    }

    /// Ends the recording with a final `At(step)` so that replay runs as long as the session did.
    pub fn finish(mut self, step: u64) -> std::io::Result<()> {
        writeln!(self.out, "        At({step}),")?;
        writeln!(self.out, "    ],\n)")?;
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cut_off_recording_is_repaired() {
        let src = "Recording(\n    scene: \"s.ron\",\n    scene_source: \"\",\n    actions: [\n        At(0), Command(Select(Forceps)),\n        At(5), Command(MoveTo((0.0, 0.01, 0.0))),\n        At(9), Command(Mo";
        let r = Recording::from_str(src, "r.ron").expect("repaired");
        assert_eq!(r.actions.len(), 4);
        assert!(is_recording(src));
    }
}

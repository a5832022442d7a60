//! Scenes and scripts: the RON files an educator writes, their schema (serde), loading, validation,
//! and errors that point at `path:line:column`.
//!
//! Owns the data types of a scene ([`Scene`]) and of a script ([`Script`]); building a tissue or running
//! a script from them is done elsewhere. Pure data: imports `chainmail` (materials, limits) and
//! `simulation` (camera and instrument types), serde and ron; never wgpu, winit or egui.
//!
//! Naming: a field's path in messages is written as in the file, e.g.
//! `tissue.layers[0].material.limits.max_stretch`.
//!
//! Loading is all or nothing: [`Scene::load`] deserializes, then validates; on any error the caller
//! gets a [`SceneError`] and no scene.

mod build;
mod cost;
mod error;
mod locate;
mod recording;
pub mod script;
mod types;
mod validate;

use std::path::Path;

pub use error::SceneError;
pub use locate::Position;
pub use recording::{FLUSH_EVERY, Recorder, Recording};
pub use script::MAX_SCRIPT_STEPS;
pub use script::{Action, CutDepth, Point, Script};
pub use types::{
    Cameras, Connective, Edge, FemMode, FemParams, Layer, LayerTissue, Pinning, Scene, SimulationSettings,
    Surface, Tissue, VolumeModel, VolumePinning, VolumeTissue,
};
pub use validate::{MAX_METRES, MAX_SCENE_ELEMENTS, MIN_SPACING};

/// The default exercise (`scenes/durotomy.ron`, the dural incision and reflection), built into the
/// binary.
pub const DEFAULT_SCENE: &str = include_str!("../../scenes/durotomy.ron");

/// Name under which [`DEFAULT_SCENE`] reports errors.
pub const DEFAULT_SCENE_PATH: &str = "scenes/durotomy.ron";

/// The RON options every scene and script is read with: `Some(..)` may be left out
/// (`tear_ratio: 1.9` means `Some(1.9)`).
pub(crate) fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// Largest scene, script or recording file read, bytes (64 MiB): a longer file is refused before it is
/// read, so that `/dev/zero` or a runaway file cannot fill the memory.
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// Reads a scene, script or recording file: a regular file (not a device, pipe or directory) of at
/// most [`MAX_FILE_BYTES`], in UTF-8. Errors name the file; invalid UTF-8 is reported at its line and
/// column.
pub fn read_file(path: impl AsRef<Path>) -> Result<String, SceneError> {
    use std::io::Read;
    let path = path.as_ref();
    let io = |source| SceneError::Io { path: path.to_path_buf(), source };
    let refuse = |why: String| io(std::io::Error::new(std::io::ErrorKind::InvalidInput, why));
    // Checked before opening, so that a pipe does not block the open.
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(refuse(format!(
            "not a regular file ({}), expected a RON file",
            if meta.is_dir() { "a directory" } else { "a device, pipe or socket" }
        )));
    }
    let too_long = |n: u64| {
        refuse(format!(
            "the file is {n} bytes long, more than the limit of {MAX_FILE_BYTES} bytes ({} MiB)",
            MAX_FILE_BYTES >> 20
        ))
    };
    if meta.len() > MAX_FILE_BYTES {
        return Err(too_long(meta.len()));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // A file that grows while it is read is still cut at the limit.
    file.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(too_long(bytes.len() as u64));
    }
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = 1 + valid.iter().filter(|&&b| b == b'\n').count();
        let last = valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let column = 1 + String::from_utf8_lossy(&valid[last..]).chars().count();
        SceneError::Parse {
            path: path.to_path_buf(),
            line,
            column,
            message: "this byte is not UTF-8 text, expected a text file in UTF-8".to_owned(),
        }
    })
}

pub(crate) fn read(path: &Path) -> Result<String, SceneError> {
    read_file(path)
}

impl Scene {
    /// Reads, parses and validates a scene file.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Self::load_with_source(path).map(|(scene, _)| scene)
    }

    /// Reads, parses and validates a scene file, and gives its text too (what a recording keeps).
    pub fn load_with_source(path: impl AsRef<Path>) -> Result<(Scene, String), SceneError> {
        let path = path.as_ref();
        let src = read(path)?;
        let scene = Self::from_str(&src, path)?;
        Ok((scene, src))
    }

    /// Parses and validates a scene from text; `path` is used only in error messages.
    pub fn from_str(src: &str, path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let scene: Scene = ron_options().from_str(src).map_err(|e| error::parse_error(path, src, &e))?;
        validate::scene(&scene).map_err(|p| p.into_error(path, src))?;
        Ok(scene)
    }

    /// The built-in default scene ([`DEFAULT_SCENE`]).
    pub fn default_scene() -> Result<Scene, SceneError> {
        Self::from_str(DEFAULT_SCENE, DEFAULT_SCENE_PATH)
    }

    /// Checks the scene's values (as [`Scene::load`] does); for scenes built in code. The error has no
    /// source to point into, so its line and column are 1:1.
    pub fn validate(&self) -> Result<(), SceneError> {
        validate::scene(self).map_err(|p| p.into_error(Path::new("<scene>"), ""))
    }

    /// The scene as pretty RON, which [`Scene::from_str`] reads back to an equal scene.
    pub fn to_ron_string(&self) -> Result<String, ron::Error> {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default().struct_names(true))
    }
}

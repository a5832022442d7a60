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
pub use script::{Action, CutDepth, Point, Script};
pub use types::{
    Cameras, Connective, Edge, FemMode, FemParams, Layer, LayerTissue, Pinning, Scene, SimulationSettings,
    Surface, Tissue, VolumeModel, VolumePinning, VolumeTissue,
};

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

/// Reads a file to a string, as a [`SceneError::Io`] on failure.
pub(crate) fn read(path: &Path) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })
}

impl Scene {
    /// Reads, parses and validates a scene file.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let src = read(path)?;
        Self::from_str(&src, path)
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

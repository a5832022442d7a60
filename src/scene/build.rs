//! From a scene to a running world: the tissue it describes, its clock and relaxation budget.

use super::types::{FemMode, Scene, Tissue, VolumeModel, VolumePinning};
use crate::chainmail::RelaxBudget;
use crate::simulation::{World, WorldConfig};
use crate::tissue::{FemSpec, LayeredSpec, Pinning, TissueError, TissueSpec, VolumeSpec};

impl Scene {
    /// The same scene at another resolution: `nu × nv` elements per layer of layered tissue, `nu`
    /// along each axis of a volume (`nv` unused). What a trainee meets does not change with it (the
    /// instruments, limits and goals are in metres), only how smooth the tissue looks. Explicit
    /// element coordinates (`u_coords`, `v_coords`) are kept, so building a scene that has them then
    /// reports their count. For benches, examples and tests that play one exercise at several
    /// resolutions.
    pub fn with_resolution(mut self, nu: u32, nv: u32) -> Self {
        match &mut self.tissue {
            Tissue::Layers(l) => l.resolution = [nu, nv],
            Tissue::Volume(v) => v.resolution = [nu; 3],
        }
        self
    }

    /// What the tissue builder needs.
    pub fn tissue_spec(&self) -> Result<TissueSpec, TissueError> {
        match &self.tissue {
            Tissue::Layers(l) => Ok(TissueSpec::Layered(LayeredSpec {
                surface: l.surface,
                resolution: [l.resolution[0] as usize, l.resolution[1] as usize],
                u_coords: Some(l.u_fractions()),
                v_coords: Some(l.v_fractions()),
                layers: l.layers.clone(),
                connective: l.connective,
                pinned: l.pinned.clone(),
            })),
            Tissue::Volume(v) => Ok(TissueSpec::Volume(VolumeSpec {
                size: v.size,
                resolution: v.resolution.map(|n| n as usize),
                material: v.material,
                color: v.color,
                pinned: match v.pinned {
                    VolumePinning::None => Pinning::None,
                    VolumePinning::Base => Pinning::Boundary,
                },
                fem: match v.model {
                    VolumeModel::ChainMail => None,
                    VolumeModel::Fem(f) => Some(FemSpec {
                        young: f.young_modulus,
                        poisson: f.poisson_ratio,
                        density: f.density,
                        damping: f.damping,
                        dynamic: f.mode == FemMode::Dynamic,
                    }),
                },
            })),
        }
    }

    /// The world settings: the scene's rate and relaxation sweeps; with `interactive`, also its
    /// relaxation time budget (which makes runs depend on the machine's speed, so headless runs leave
    /// it out and stay bit-for-bit reproducible).
    pub fn world_config(&self, interactive: bool) -> WorldConfig {
        let s = &self.simulation;
        WorldConfig {
            rate_hz: s.rate_hz as f64,
            relax: RelaxBudget {
                max_sweeps: s.relax_sweeps,
                max_time: interactive.then(|| s.relax_budget()),
                tolerance: 0.0,
            },
            sizes: self.instrument_sizes,
            ..WorldConfig::default()
        }
    }

    /// Builds the world the scene describes.
    pub fn build_world(&self, interactive: bool) -> Result<World, TissueError> {
        let mut world = World::build(&self.tissue_spec()?, self.world_config(interactive))?;
        if let Some(goals) = &self.goals {
            world.set_regions(goals.surface_regions());
            world.set_incision(goals.incision.iter().map(|&(u, v)| [u, v]).collect());
        }
        Ok(world)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scene at another resolution differs from it in that alone, and builds that many elements:
    /// `nu × nv` per layer, `nu³` in a volume.
    #[test]
    fn a_scene_at_another_resolution_differs_in_that_alone() {
        let layered =
            Scene::from_str(include_str!("../../scenes/meninges.ron"), "meninges.ron").expect("scene");
        let volume = Scene::from_str(include_str!("../../scenes/volume.ron"), "volume.ron").expect("scene");
        for (scene, [nu, nv], want) in [(layered, [24, 18], 2 * 24 * 18), (volume, [7, 99], 7 * 7 * 7)] {
            let at = scene.clone().with_resolution(nu, nv);
            let mut back = at.clone();
            match (&mut back.tissue, &scene.tissue) {
                (Tissue::Layers(b), Tissue::Layers(s)) => b.resolution = s.resolution,
                (Tissue::Volume(b), Tissue::Volume(s)) => b.resolution = s.resolution,
                _ => panic!("the tissue's kind changed"),
            }
            assert_eq!(back, scene, "only the resolution changes");
            let world = at.build_world(false).expect("world");
            assert_eq!(world.tissue().body().element_count(), want);
        }
    }
}

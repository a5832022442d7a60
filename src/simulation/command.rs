//! What the world is told between steps: what the hand does with the instrument, and changes to the
//! world's own settings (a material tuned live, the relaxation budget). Commands are gathered as they
//! come and consumed once, at the start of the next step; recordings write them as they are.

use serde::{Deserialize, Serialize};

use crate::chainmail::{ElementId, Material, MaterialId};
use crate::snapshot::InstrumentKind;
use crate::tissue::CutDepth;

/// A command to the world.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub enum Command {
    // What the hand does with the instrument.
    /// Take another instrument (ends any cut; what the forceps hold stays held until `Release`).
    Select(InstrumentKind),
    /// Move the tip to a world point.
    MoveTo([f32; 3]),
    /// Forceps: close on the nearest element within reach of the tip.
    Grasp,
    /// Forceps: close on a given element (from picking, see `World::element_at`).
    GraspElement(ElementId),
    /// Forceps: open.
    Release,
    /// Scalpel: set the depth of the blade.
    SetDepth(CutDepth),
    /// Scalpel: press the blade; moving the tip now cuts.
    BeginCut,
    /// Scalpel: lift the blade.
    EndCut,
    /// Rotate the instrument about its axis, radians.
    Roll(f32),
    /// Point the instrument: unit vector from the tip to the handle.
    SetAxis([f32; 3]),

    // The world's settings.
    /// Retune a material of the tissue live (a slider), so that recordings replay it.
    SetMaterial(MaterialId, Material),
    /// Change the most relaxation sweeps per step.
    SetRelaxSweeps(u32),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serializes_as_recordings_write_it() {
        let write = |c: &Command| ron::to_string(c).expect("written");
        let read = |s: &str| ron::from_str::<Command>(s).expect("read");
        assert_eq!(write(&Command::Select(InstrumentKind::Forceps)), "Select(Forceps)");
        assert_eq!(read("MoveTo((0.0, 0.01, 0.0))"), Command::MoveTo([0.0, 0.01, 0.0]));
        assert_eq!(read(&write(&Command::SetRelaxSweeps(7))), Command::SetRelaxSweeps(7));
    }
}

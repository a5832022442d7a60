//! What the world is told between steps: an instrument command, or a change to the world's own
//! settings (a material tuned live, the relaxation budget). Commands are gathered as they come and
//! consumed once, at the start of the next step.

use serde::{Deserialize, Serialize};

use crate::chainmail::{ElementId, Material, MaterialId};
use crate::instrument::Command as InstrumentCommand;
use crate::snapshot::InstrumentKind;
use crate::tissue::CutDepth;

/// A command to the world.
///
/// Serialized flat, one variant name per command (`Select(Forceps)`, `SetMaterial(..)`), as
/// recordings have always written them.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(from = "Flat", into = "Flat")]
pub enum Command {
    /// Something the instrument does.
    Instrument(InstrumentCommand),
    /// Retune a material of the tissue live (a slider), so that recordings replay it.
    SetMaterial(MaterialId, Material),
    /// Change the most relaxation sweeps per step.
    SetRelaxSweeps(u32),
}

impl From<InstrumentCommand> for Command {
    fn from(c: InstrumentCommand) -> Self {
        Command::Instrument(c)
    }
}

/// The serialized form: every command at one level, the names recordings use.
#[derive(Serialize, Deserialize, Clone)]
enum Flat {
    Select(InstrumentKind),
    MoveTo([f32; 3]),
    Grasp,
    GraspElement(ElementId),
    Release,
    SetDepth(CutDepth),
    BeginCut,
    EndCut,
    Roll(f32),
    SetAxis([f32; 3]),
    SetMaterial(MaterialId, Material),
    SetRelaxSweeps(u32),
}

impl From<Flat> for Command {
    fn from(f: Flat) -> Self {
        use InstrumentCommand as I;
        match f {
            Flat::Select(k) => I::Select(k).into(),
            Flat::MoveTo(p) => I::MoveTo(p).into(),
            Flat::Grasp => I::Grasp.into(),
            Flat::GraspElement(e) => I::GraspElement(e).into(),
            Flat::Release => I::Release.into(),
            Flat::SetDepth(d) => I::SetDepth(d).into(),
            Flat::BeginCut => I::BeginCut.into(),
            Flat::EndCut => I::EndCut.into(),
            Flat::Roll(r) => I::Roll(r).into(),
            Flat::SetAxis(a) => I::SetAxis(a).into(),
            Flat::SetMaterial(id, m) => Command::SetMaterial(id, m),
            Flat::SetRelaxSweeps(n) => Command::SetRelaxSweeps(n),
        }
    }
}

impl From<Command> for Flat {
    fn from(c: Command) -> Self {
        use InstrumentCommand as I;
        match c {
            Command::Instrument(i) => match i {
                I::Select(k) => Flat::Select(k),
                I::MoveTo(p) => Flat::MoveTo(p),
                I::Grasp => Flat::Grasp,
                I::GraspElement(e) => Flat::GraspElement(e),
                I::Release => Flat::Release,
                I::SetDepth(d) => Flat::SetDepth(d),
                I::BeginCut => Flat::BeginCut,
                I::EndCut => Flat::EndCut,
                I::Roll(r) => Flat::Roll(r),
                I::SetAxis(a) => Flat::SetAxis(a),
            },
            Command::SetMaterial(id, m) => Flat::SetMaterial(id, m),
            Command::SetRelaxSweeps(n) => Flat::SetRelaxSweeps(n),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serializes_flat_as_recordings_write_it() {
        let c: Command = InstrumentCommand::Select(InstrumentKind::Forceps).into();
        let write = |c: &Command| ron::to_string(c).expect("written");
        let read = |s: &str| ron::from_str::<Command>(s).expect("read");
        assert_eq!(write(&c), "Select(Forceps)");
        assert_eq!(read("Select(Forceps)"), c);
        let c = Command::SetRelaxSweeps(7);
        assert_eq!(read(&write(&c)), c);
        let c: Command = InstrumentCommand::MoveTo([0.0, 0.01, 0.0]).into();
        assert_eq!(read("MoveTo((0.0, 0.01, 0.0))"), c);
    }
}

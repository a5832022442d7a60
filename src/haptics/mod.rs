//! Haptic devices: a hand on a device moves the instrument and feels the tissue's force.
//!
//! A [`HapticDevice`] is read (pose and buttons) and written (a force) once per simulation step. The
//! device does not drive the instrument directly: a [`Coupling`] (virtual coupling, Colgate, Stanley
//! and Brown 1995) joins them with a spring of [`Coupling::stiffness`], so the hand never feels a
//! stiffer tissue than the device can render stably. Each step the instrument's proxy takes one
//! Newton step towards where the coupling spring balances the tissue's force, with a secant estimate
//! of the tissue's stiffness, so the loop stays stable however stiff the tissue is. On top, a
//! passivity observer and controller (Hannaford and Ryu 2002) counts the energy the coupling has given
//! the hand and damps any surplus, and the force is clamped to the device's limit.
//!
//! Backends: the mouse ([`MouseDevice`], the default: no device, today's behaviour), a scripted
//! [`SimulatedDevice`] for tests, and the Haply Inverse3 through the `haply` crate behind the `haply`
//! cargo feature. The device's moves reach the world as ordinary instrument commands, so sessions
//! driven by a device are recorded and replay bit for bit.
//!
//! Must not import wgpu, winit or egui.

#[cfg(feature = "haply")]
mod inverse3;

#[cfg(feature = "haply")]
pub use inverse3::Inverse3;

use thiserror::Error;

use crate::simulation::{Command, InstrumentKind};

/// What a device reports in one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DeviceState {
    /// Position of the handle in the device's frame, metres (Y up).
    pub position: [f32; 3],
    /// Buttons held, bit 0 the main one (close the forceps, press the blade).
    pub buttons: u32,
}

/// Why a device stopped being usable.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DeviceError {
    /// It was not found or went away.
    #[error("{device}: {reason}")]
    Lost {
        /// The device.
        device: String,
        /// What happened.
        reason: String,
    },
    /// It reported something that cannot be a pose (not a finite number).
    #[error("{device}: bad input: {reason}")]
    BadInput {
        /// The device.
        device: String,
        /// What was wrong.
        reason: String,
    },
}

/// A device read and written at the simulation's rate.
pub trait HapticDevice: Send {
    /// A short name for messages.
    fn name(&self) -> &str;
    /// The pose and buttons now; `None` when the device has nothing to say (the mouse drives).
    fn read(&mut self) -> Result<Option<DeviceState>, DeviceError>;
    /// Sends the force the hand should feel, newtons, world axes.
    fn write_force(&mut self, force: [f32; 3]) -> Result<(), DeviceError>;
    /// Largest force it may be sent, newtons.
    fn max_force(&self) -> f32;
}

/// No device: the mouse moves the instrument (through the window's input), nothing is felt.
#[derive(Clone, Copy, Debug, Default)]
pub struct MouseDevice;

impl HapticDevice for MouseDevice {
    fn name(&self) -> &str {
        "mouse"
    }

    fn read(&mut self) -> Result<Option<DeviceState>, DeviceError> {
        Ok(None)
    }

    fn write_force(&mut self, _force: [f32; 3]) -> Result<(), DeviceError> {
        Ok(())
    }

    fn max_force(&self) -> f32 {
        0.0
    }
}

/// A device that plays a path given as a function of the step, and keeps what it was sent: for tests.
pub struct SimulatedDevice {
    path: Box<dyn FnMut(u64) -> Option<DeviceState> + Send>,
    step: u64,
    max_force: f32,
    /// Every force it was sent, in order.
    pub forces: Vec<[f32; 3]>,
}

impl SimulatedDevice {
    /// A device following `path(step)` (`None`: it disappears), with a force limit in newtons.
    pub fn new(max_force: f32, path: impl FnMut(u64) -> Option<DeviceState> + Send + 'static) -> Self {
        Self { path: Box::new(path), step: 0, max_force, forces: Vec::new() }
    }
}

impl HapticDevice for SimulatedDevice {
    fn name(&self) -> &str {
        "simulated device"
    }

    fn read(&mut self) -> Result<Option<DeviceState>, DeviceError> {
        let state = (self.path)(self.step);
        self.step += 1;
        match state {
            Some(s) => Ok(Some(s)),
            None => {
                Err(DeviceError::Lost { device: self.name().into(), reason: "it stopped answering".into() })
            }
        }
    }

    fn write_force(&mut self, force: [f32; 3]) -> Result<(), DeviceError> {
        self.forces.push(force);
        Ok(())
    }

    fn max_force(&self) -> f32 {
        self.max_force
    }
}

/// Opens a device by name: `mouse`, or `inverse3` (with the `haply` feature). Anything that cannot be
/// opened gives the mouse and one line saying why.
pub fn open(name: &str) -> (Box<dyn HapticDevice>, Option<String>) {
    match name {
        "mouse" | "" => (Box::new(MouseDevice), None),
        #[cfg(feature = "haply")]
        "inverse3" => match Inverse3::connect() {
            Ok(d) => (Box::new(d), None),
            Err(e) => (Box::new(MouseDevice), Some(format!("no haptic device ({e}); the mouse drives"))),
        },
        #[cfg(not(feature = "haply"))]
        "inverse3" => (
            Box::new(MouseDevice),
            Some("no haptic device (built without the `haply` feature); the mouse drives".into()),
        ),
        other => (
            Box::new(MouseDevice),
            Some(format!("no haptic device called {other:?} (expected mouse or inverse3); the mouse drives")),
        ),
    }
}

/// Coupling spring used with a device, newtons per metre.
pub const COUPLING_STIFFNESS: f32 = 500.0;

/// A device joined to a world's instrument: read, coupled and written once per step.
pub struct HapticLink {
    device: Box<dyn HapticDevice>,
    coupling: Option<Coupling>,
    last_force: [f32; 3],
}

impl Default for HapticLink {
    fn default() -> Self {
        Self::new(Box::new(MouseDevice))
    }
}

impl HapticLink {
    /// A link to `device`.
    pub fn new(device: Box<dyn HapticDevice>) -> Self {
        Self { device, coupling: None, last_force: [0.0; 3] }
    }

    /// The device's name.
    pub fn name(&self) -> &str {
        self.device.name()
    }

    /// The coupling, once the device has reported.
    pub fn coupling(&self) -> Option<&Coupling> {
        self.coupling.as_ref()
    }

    /// The force last sent to the device, newtons.
    pub fn last_force(&self) -> [f32; 3] {
        self.last_force
    }

    /// The device itself.
    pub fn device(&self) -> &dyn HapticDevice {
        self.device.as_ref()
    }

    /// Before a step: reads the device, sends it the force of the last step through the coupling, and
    /// returns the instrument commands to give the world (and to record) for this step. A device with
    /// nothing to say gives none. A lost device or a reading that is not a pose is an error: the
    /// caller says so and goes on with the mouse.
    pub fn exchange(&mut self, world: &crate::simulation::World) -> Result<Commands, DeviceError> {
        let Some(state) = self.device.read()? else { return Ok(Commands::new()) };
        let max = self.device.max_force();
        let coupling = self
            .coupling
            .get_or_insert_with(|| Coupling::new(COUPLING_STIFFNESS, max, world.instrument().target));
        let kind = world.instrument().kind;
        let dt = (1.0 / world.config().rate_hz) as f32;
        let out = coupling
            .step(state, world.forces().in_hand(), kind, dt)
            .map_err(|reason| DeviceError::BadInput { device: self.device.name().into(), reason })?;
        self.device.write_force(out.force)?;
        self.last_force = out.force;
        Ok(out.commands)
    }
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A step's instrument commands from a device: a move, and a press or release of the main button. Held
/// in place, so that a device read a thousand times a second allocates nothing.
pub type Commands = arrayvec::ArrayVec<Command, 2>;

/// What the coupling asks of the world and of the device in one step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CouplingOutput {
    /// Instrument commands for this step (a move, and a grasp or cut on a button change).
    pub commands: Commands,
    /// The force to send to the device, newtons.
    pub force: [f32; 3],
}

/// The virtual coupling between a device and the instrument, with its passivity controller.
#[derive(Clone, Debug, PartialEq)]
pub struct Coupling {
    /// Coupling spring, newtons per metre.
    pub stiffness: f32,
    /// Largest force sent, newtons.
    pub max_force: f32,
    /// World point the device's first reading maps to.
    origin: [f32; 3],
    /// The device's first reading (its frame's origin for the session).
    device_origin: Option<[f32; 3]>,
    proxy: [f32; 3],
    last_proxy: [f32; 3],
    last_tissue: [f32; 3],
    tissue_stiffness: f32,
    last_device: Option<[f32; 3]>,
    last_force: [f32; 3],
    /// Energy the coupling has given the hand, joules (positive would be a gain).
    energy: f64,
    buttons: u32,
}

impl Coupling {
    /// A coupling of `stiffness` N/m, clamped to `max_force` N, whose device origin maps to `origin`
    /// (the instrument's position when the device takes over).
    pub fn new(stiffness: f32, max_force: f32, origin: [f32; 3]) -> Self {
        Self {
            stiffness,
            max_force,
            origin,
            device_origin: None,
            proxy: origin,
            last_proxy: origin,
            last_tissue: [0.0; 3],
            tissue_stiffness: 0.0,
            last_device: None,
            last_force: [0.0; 3],
            energy: 0.0,
            buttons: 0,
        }
    }

    /// Energy given to the hand so far, joules: it never grows above zero by more than one step's
    /// worth (the controller damps the surplus away in the next step).
    pub fn energy(&self) -> f64 {
        self.energy
    }

    /// One step: the device's reading and the tissue's force on the instrument in hand (from the last
    /// step) give the instrument's commands and the device's force. A reading that is not a finite
    /// pose is refused.
    pub fn step(
        &mut self,
        state: DeviceState,
        tissue: [f32; 3],
        kind: InstrumentKind,
        dt: f32,
    ) -> Result<CouplingOutput, String> {
        if !state.position.iter().all(|x| x.is_finite()) {
            return Err(format!("position {:?} is not a finite point", state.position));
        }
        let tissue = if tissue.iter().all(|x| x.is_finite()) { tissue } else { [0.0; 3] };
        let start = *self.device_origin.get_or_insert(state.position);
        let x = [0, 1, 2].map(|k| self.origin[k] + state.position[k] - start[k]);
        // Passivity observer: the work the last force did on the hand over the last interval.
        if let Some(last) = self.last_device {
            self.energy += f64::from(dot(self.last_force, sub(x, last)));
        }
        // The tissue's stiffness along the proxy's last move (secant, never negative), decaying.
        let dp = sub(self.proxy, self.last_proxy);
        let dp2 = dot(dp, dp);
        if dp2 > 1e-18 {
            let k = -dot(sub(tissue, self.last_tissue), dp) / dp2;
            self.tissue_stiffness = self.tissue_stiffness.max(0.0) * 0.9;
            if k.is_finite() {
                self.tissue_stiffness = self.tissue_stiffness.max(k);
            }
        }
        self.last_tissue = tissue;
        self.last_proxy = self.proxy;
        // Newton step of the proxy towards k_c (x − p) + F_tissue(p) = 0.
        let denom = self.stiffness + self.tissue_stiffness.max(0.0);
        let r = [0, 1, 2].map(|k| self.stiffness * (x[k] - self.proxy[k]) + tissue[k]);
        self.proxy = [0, 1, 2].map(|k| self.proxy[k] + r[k] / denom);
        // The coupling spring's force on the hand.
        let mut force = [0, 1, 2].map(|k| self.stiffness * (self.proxy[k] - x[k]));
        // Passivity controller: a surplus of energy given is taken back by damping the motion.
        if let Some(last) = self.last_device {
            let v = sub(x, last).map(|c| c / dt);
            let v2 = dot(v, v);
            if self.energy > 0.0 && v2 > 0.0 {
                let alpha = (self.energy / (f64::from(v2) * f64::from(dt))) as f32;
                force = [0, 1, 2].map(|k| force[k] - alpha * v[k]);
            }
        }
        let m = dot(force, force).sqrt();
        if m > self.max_force {
            force = force.map(|c| c * self.max_force / m);
        }
        self.last_device = Some(x);
        self.last_force = force;
        // Commands: the move, and a press or release of the main button.
        let mut commands = Commands::new();
        commands.push(Command::MoveTo(self.proxy));
        let (was, now) = (self.buttons & 1 != 0, state.buttons & 1 != 0);
        if now != was {
            commands.push(match (kind, now) {
                (InstrumentKind::Forceps, true) => Command::Grasp,
                (InstrumentKind::Forceps, false) => Command::Release,
                (InstrumentKind::Scalpel, true) => Command::BeginCut,
                (InstrumentKind::Scalpel, false) => Command::EndCut,
                (InstrumentKind::Probe, _) => Command::MoveTo(self.proxy),
            });
        }
        self.buttons = state.buttons;
        Ok(CouplingOutput { commands, force })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stiff_wall_is_felt_through_the_coupling_without_energy_gain() {
        // A wall at y = 0 of 50 kN/m, far stiffer than the 500 N/m coupling, pressed and let go.
        let mut c = Coupling::new(500.0, 3.0, [0.0, 0.01, 0.0]);
        let wall = |p: [f32; 3]| [0.0, if p[1] < 0.0 { -50_000.0 * p[1] } else { 0.0 }, 0.0];
        let mut proxy = [0.0, 0.01, 0.0];
        let mut peak = 0.0f32;
        for step in 0..4000u64 {
            let t = step as f32 * 1e-3;
            let y = -0.02 * (std::f32::consts::PI * t / 4.0).sin();
            let s = DeviceState { position: [0.0, y, 0.0], buttons: 0 };
            let out = c.step(s, wall(proxy), InstrumentKind::Probe, 1e-3).unwrap_or_else(|e| panic!("{e}"));
            if let Some(Command::MoveTo(p)) = out.commands.first() {
                proxy = *p;
            }
            let f = dot(out.force, out.force).sqrt();
            assert!(f <= 3.0 + 1e-4);
            peak = peak.max(f);
            assert!(c.energy() < 1e-4, "step {step}: energy {}", c.energy());
        }
        assert!(peak > 2.9, "the wall was felt: {peak}");
    }

    #[test]
    fn nan_is_refused() {
        let mut c = Coupling::new(500.0, 3.0, [0.0; 3]);
        let s = DeviceState { position: [f32::NAN, 0.0, 0.0], buttons: 0 };
        assert!(c.step(s, [0.0; 3], InstrumentKind::Forceps, 1e-3).is_err());
    }
}

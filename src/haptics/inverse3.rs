//! The Haply Inverse3 through Haply's Inverse Service (`haply` crate, a websocket client): a background
//! thread runs the client's async loop, publishes the latest cursor position and takes the latest
//! force; the simulation reads and writes without waiting for the network.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::{DeviceError, DeviceState, HapticDevice};

/// The service's addresses on this machine (Haply's defaults).
const HTTP_BASE: &str = "http://localhost:10001";
const WS_URL: &str = "ws://localhost:10001/";
/// Largest force sent, newtons (well inside the Inverse3's rating).
const MAX_FORCE: f32 = 3.0;
/// A device whose state is older than this is taken as gone.
const STALE: Duration = Duration::from_millis(250);

#[derive(Default)]
struct Shared {
    state: Option<(DeviceState, web_time::Instant)>,
    force: [f32; 3],
    error: Option<String>,
    stop: bool,
}

/// An Inverse3 behind the Inverse Service.
pub struct Inverse3 {
    shared: Arc<Mutex<Shared>>,
}

fn lost(reason: impl Into<String>) -> DeviceError {
    DeviceError::Lost { device: "Inverse3".into(), reason: reason.into() }
}

impl Inverse3 {
    /// Connects to the service and waits up to a second for a device to report.
    pub fn connect() -> Result<Self, DeviceError> {
        let shared = Arc::new(Mutex::new(Shared::default()));
        let inner = Arc::clone(&shared);
        std::thread::Builder::new()
            .name("inverse3".into())
            .spawn(move || run(inner))
            .map_err(|e| lost(format!("cannot start its thread: {e}")))?;
        let start = web_time::Instant::now();
        while start.elapsed() < Duration::from_secs(1) {
            std::thread::sleep(Duration::from_millis(10));
            let s = shared.lock().map_err(|_| lost("its thread failed"))?;
            if let Some(e) = &s.error {
                return Err(lost(e.clone()));
            }
            if s.state.is_some() {
                drop(s);
                return Ok(Self { shared });
            }
        }
        if let Ok(mut s) = shared.lock() {
            s.stop = true;
        }
        Err(lost(format!("no Inverse3 reported within a second at {WS_URL}")))
    }
}

fn run(shared: Arc<Mutex<Shared>>) {
    let fail = |shared: &Arc<Mutex<Shared>>, e: String| {
        if let Ok(mut s) = shared.lock() {
            s.error = Some(e);
        }
    };
    let runtime = match tokio::runtime::Builder::new_current_thread().enable_all().build() {
        Ok(r) => r,
        Err(e) => return fail(&shared, format!("no async runtime: {e}")),
    };
    runtime.block_on(async {
        let mut device = match haply::HaplyDevice::new(HTTP_BASE, WS_URL).await {
            Ok(d) => d,
            Err(e) => return fail(&shared, format!("the Inverse Service at {WS_URL} did not answer: {e}")),
        };
        loop {
            let data = match device.read_state().await {
                Ok(d) => d,
                Err(e) => return fail(&shared, e.to_string()),
            };
            let Some(inv) = data.inverse3.first() else {
                tokio::time::sleep(Duration::from_millis(1)).await;
                continue;
            };
            let id = inv.device_id.clone();
            let position: [f32; 3] = inv.state.cursor_position.map(Into::into).unwrap_or([0.0; 3]);
            let buttons = data.verse_grip.first().and_then(|g| g.state.button).map(u32::from).unwrap_or(0);
            let force = {
                let Ok(mut s) = shared.lock() else { return };
                if s.stop {
                    return;
                }
                s.state = Some((DeviceState { position, buttons }, web_time::Instant::now()));
                s.force
            };
            let input = haply::ForceInput { device_id: id, forces: force.into() };
            if let Err(e) = device.update_force(vec![input], Some(true), Some(true)).await {
                return fail(&shared, e.to_string());
            }
            tokio::time::sleep(Duration::from_millis(1)).await;
        }
    });
}

impl HapticDevice for Inverse3 {
    fn name(&self) -> &str {
        "Inverse3"
    }

    fn read(&mut self) -> Result<Option<DeviceState>, DeviceError> {
        let s = self.shared.lock().map_err(|_| lost("its thread failed"))?;
        if let Some(e) = &s.error {
            return Err(lost(e.clone()));
        }
        match s.state {
            Some((state, at)) if at.elapsed() < STALE => Ok(Some(state)),
            Some(_) => Err(lost("it stopped reporting")),
            None => Ok(None),
        }
    }

    fn write_force(&mut self, force: [f32; 3]) -> Result<(), DeviceError> {
        let mut s = self.shared.lock().map_err(|_| lost("its thread failed"))?;
        s.force = force;
        Ok(())
    }

    fn max_force(&self) -> f32 {
        MAX_FORCE
    }
}

impl Drop for Inverse3 {
    fn drop(&mut self) {
        if let Ok(mut s) = self.shared.lock() {
            s.stop = true;
            s.force = [0.0; 3];
        }
    }
}

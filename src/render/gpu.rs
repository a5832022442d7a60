//! The device context shared by every view: instance, adapter, device and queue.

use super::RenderError;

/// A wgpu instance, adapter, device and queue.
///
/// Headless: [`Gpu::headless`] (native) or `Gpu::request(Gpu::instance(), None).await`.
///
/// For a window the app, in `ApplicationHandler::resumed`:
/// 1. `let instance = Gpu::instance_for_display(Box::new(event_loop.owned_display_handle()));`
/// 2. `let surface = instance.create_surface(window.clone())?;` (an `Arc<Window>`, so it is `'static`);
/// 3. `let gpu = pollster::block_on(Gpu::request(instance, Some(&surface)))?;`
/// 4. configures the surface (any format from `surface.get_capabilities(&gpu.adapter)`; sRGB or not, the
///    renderer encodes correctly) and builds one [`SceneRenderer`](super::SceneRenderer) for that format
///    and one [`SceneView`](super::SceneView) per window, resized with the window.
///
/// A second window reuses the same `Gpu` (create its surface from `gpu.instance`).
#[derive(Debug)]
pub struct Gpu {
    /// The instance; windows create their surfaces from it.
    pub instance: wgpu::Instance,
    /// The adapter chosen.
    pub adapter: wgpu::Adapter,
    /// The logical device.
    pub device: wgpu::Device,
    /// The device's queue.
    pub queue: wgpu::Queue,
}

impl Gpu {
    /// An instance with no display handle, backends from `WGPU_BACKEND` if set (all by default).
    pub fn instance() -> wgpu::Instance {
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
    }

    /// An instance for windows: `display` is the event loop's display handle (winit's
    /// `event_loop.owned_display_handle()`), which the GL backend needs to present; backends from
    /// `WGPU_BACKEND` if set.
    pub fn instance_for_display(display: Box<dyn wgpu::wgt::WgpuHasDisplayHandle>) -> wgpu::Instance {
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(display))
    }

    /// Picks an adapter from `instance` (able to present to `compatible_surface` when given) and opens
    /// a device with limits a WebGL2-class device also has, raised to what the adapter offers for
    /// texture sizes.
    ///
    /// Does not fall back to another backend by itself: [`Gpu::headless`] does that.
    pub async fn request(
        instance: wgpu::Instance,
        compatible_surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, RenderError> {
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface,
                ..Default::default()
            })
            .await
            .map_err(|source| RenderError::NoAdapter { tried: "the instance's backends".into(), source })?;
        Self::open(instance, adapter).await
    }

    async fn open(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<Self, RenderError> {
        let limits = wgpu::Limits::downlevel_webgl2_defaults()
            .using_resolution(adapter.limits())
            .using_alignment(adapter.limits());
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("dissect device"),
                required_features: wgpu::Features::empty(),
                required_limits: limits,
                ..Default::default()
            })
            .await?;
        // An error that no error scope catches (a buffer over the device's limit, a lost device) is
        // logged rather than left to wgpu's default handler, which panics.
        device.on_uncaptured_error(std::sync::Arc::new(|e: wgpu::Error| {
            log::error!("GPU error, the frame may be incomplete: {e}");
        }));
        Ok(Self { instance, adapter, device, queue })
    }

    /// A device with no window: the default backends (Vulkan first on Linux), and if none gives an
    /// adapter, GL alone. Blocks; native only.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn headless() -> Result<Self, RenderError> {
        pollster::block_on(async {
            let first = Self::request(Self::instance(), None).await;
            let Err(RenderError::NoAdapter { .. }) = first else {
                return first;
            };
            let gl = wgpu::Instance::new(wgpu::InstanceDescriptor {
                backends: wgpu::Backends::GL,
                ..wgpu::InstanceDescriptor::new_without_display_handle()
            });
            Self::request(gl, None).await.map_err(|e| match e {
                RenderError::NoAdapter { source, .. } => RenderError::NoAdapter {
                    tried: "default backends (Vulkan, GL), then GL alone".into(),
                    source,
                },
                other => other,
            })
        })
    }

    /// Whether the adapter is a CPU rasteriser (lavapipe, llvmpipe). There 4× MSAA costs about 3 to 4
    /// times a single-sampled frame, so an interactive window may prefer
    /// [`SceneRenderer::with_samples`](super::SceneRenderer::with_samples) with 1.
    pub fn is_software(&self) -> bool {
        self.adapter.get_info().device_type == wgpu::DeviceType::Cpu
    }

    /// One line naming the adapter and backend, for logs and test messages.
    pub fn describe(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
    }
}

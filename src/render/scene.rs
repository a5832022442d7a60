//! The scene pipelines and the GPU copies of a snapshot: layers, fibres, instrument, cut path.
//!
//! [`SceneRenderer::update`] uploads a [`Snapshot`] into buffers it keeps between frames (positions and
//! normals every frame with `write_buffer`; index buffers only when a layer's `topology_version` changes;
//! new buffers only when something grows). [`SceneRenderer::render`] records one pass into a
//! [`SceneView`], which owns what differs per window or camera: the multisampled colour and depth
//! targets and the camera uniform.

use std::num::NonZeroU64;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use super::camera::OrbitCamera;
use super::mesh::{self, Part};
use super::{Gpu, RenderError};
use crate::snapshot::Snapshot;

const MESH_WGSL: &str =
    concat!(include_str!("../../shaders/common.wgsl"), include_str!("../../shaders/mesh.wgsl"));
const LINES_WGSL: &str =
    concat!(include_str!("../../shaders/common.wgsl"), include_str!("../../shaders/lines.wgsl"));
const BACKGROUND_WGSL: &str =
    concat!(include_str!("../../shaders/common.wgsl"), include_str!("../../shaders/background.wgsl"));

/// Depth buffer format of every [`SceneView`].
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Samples per pixel when the adapter supports it (else 1).
pub const MSAA_SAMPLES: u32 = 4;

/// Colours (linear RGB) and sizes of what is not in the snapshot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    /// Connective fibres.
    pub fibre_color: [f32; 3],
    /// Fibre width in pixels at a 800-pixel-tall view (scaled with the view height, at least 1 px).
    pub fibre_width_px: f32,
    /// The scalpel stroke being drawn.
    pub cut_color: [f32; 3],
    /// Cut path width in pixels at a 800-pixel-tall view.
    pub cut_width_px: f32,
    /// Steel parts of the instruments.
    pub steel_color: [f32; 3],
    /// The scalpel handle.
    pub handle_color: [f32; 3],
}

impl Default for Style {
    fn default() -> Self {
        Self {
            fibre_color: [0.92, 0.86, 0.62],
            fibre_width_px: 2.5,
            cut_color: [0.1, 0.95, 0.35],
            cut_width_px: 4.0,
            steel_color: [0.62, 0.65, 0.7],
            handle_color: [0.12, 0.14, 0.18],
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct CameraUniform {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light: [f32; 4],
    viewport: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ObjectUniform {
    model: [[f32; 4]; 4],
    color: [f32; 4],
    params: [f32; 4],
}

const OBJECT_SIZE: u64 = std::mem::size_of::<ObjectUniform>() as u64;

/// Counts of the expensive uploads since the renderer was made, to check that steady frames only
/// rewrite vertex data.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UploadStats {
    /// Calls to [`SceneRenderer::update`].
    pub updates: u64,
    /// Layer index buffers rewritten (a new layer or a `topology_version` change).
    pub index_rebuilds: u64,
    /// GPU buffers reallocated because their data outgrew them.
    pub reallocations: u64,
}

/// A GPU buffer that keeps its allocation and grows (by half again) only when data outgrows it.
#[derive(Debug)]
struct GrowBuffer {
    buffer: wgpu::Buffer,
    capacity: u64,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl GrowBuffer {
    fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages, bytes: u64) -> Self {
        let usage = usage | wgpu::BufferUsages::COPY_DST;
        let capacity = bytes.max(16).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: capacity,
            usage,
            mapped_at_creation: false,
        });
        Self { buffer, capacity, usage, label }
    }

    /// Writes `data` at offset 0, reallocating first if it does not fit. Returns whether it reallocated.
    fn write(&mut self, gpu: &Gpu, data: &[u8]) -> bool {
        let len = data.len() as u64;
        let grew = len > self.capacity;
        if grew {
            *self =
                Self::new(&gpu.device, self.label, self.usage, len.max(self.capacity + self.capacity / 2));
        }
        if len > 0 {
            gpu.queue.write_buffer(&self.buffer, 0, data);
        }
        grew
    }
}

#[derive(Debug)]
struct LayerGpu {
    positions: GrowBuffer,
    normals: GrowBuffer,
    indices: GrowBuffer,
    index_count: u32,
    vertex_count: u32,
    /// Largest index in the current index buffer (checked against the vertex count every frame).
    max_index: u32,
    topology_version: Option<u64>,
}

#[derive(Debug)]
struct PartGpu {
    positions: wgpu::Buffer,
    normals: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
}

/// Pipelines and the GPU-side copy of the latest snapshot. One per device; shared by all views.
#[derive(Debug)]
pub struct SceneRenderer {
    format: wgpu::TextureFormat,
    sample_count: u32,
    style: Style,
    camera_layout: wgpu::BindGroupLayout,
    mesh_pipeline: wgpu::RenderPipeline,
    line_pipeline: wgpu::RenderPipeline,
    overlay_line_pipeline: wgpu::RenderPipeline,
    background_pipeline: wgpu::RenderPipeline,
    object_layout: wgpu::BindGroupLayout,
    objects: GrowBuffer,
    object_bind_group: wgpu::BindGroup,
    object_stride: u64,
    object_scratch: Vec<u8>,
    layers: Vec<LayerGpu>,
    parts: Vec<PartGpu>,
    instrument: [Option<Part>; 2],
    fibres: GrowBuffer,
    fibre_count: u32,
    cut: GrowBuffer,
    cut_count: u32,
    cut_scratch: Vec<[[f32; 3]; 2]>,
    stats: UploadStats,
}

/// What one view (a window, or an offscreen image) needs besides the shared [`SceneRenderer`]: its
/// multisampled colour target, depth buffer and camera uniform. Make one per view: the camera uniform is
/// written when the view is rendered, so two cameras in one submission need two views.
#[derive(Debug)]
pub struct SceneView {
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    sample_count: u32,
    msaa: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
    camera_buffer: wgpu::Buffer,
    camera_bind_group: wgpu::BindGroup,
}

impl SceneView {
    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Recreates the targets for a new size (a resized window). No-op if the size is unchanged.
    pub fn resize(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<(), RenderError> {
        if (width, height) == (self.width, self.height) {
            return Ok(());
        }
        let (msaa, depth) = create_targets(gpu, self.format, self.sample_count, width, height)?;
        self.msaa = msaa;
        self.depth = depth;
        self.width = width;
        self.height = height;
        Ok(())
    }
}

fn check_size(gpu: &Gpu, width: u32, height: u32) -> Result<(), RenderError> {
    let max = gpu.device.limits().max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(RenderError::BadSize { width, height, max });
    }
    Ok(())
}

fn create_targets(
    gpu: &Gpu,
    format: wgpu::TextureFormat,
    sample_count: u32,
    width: u32,
    height: u32,
) -> Result<(Option<wgpu::TextureView>, wgpu::TextureView), RenderError> {
    check_size(gpu, width, height)?;
    let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
    let texture = |label, format| {
        gpu.device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
            .create_view(&wgpu::TextureViewDescriptor::default())
    };
    let msaa = (sample_count > 1).then(|| texture("scene msaa colour", format));
    Ok((msaa, texture("scene depth", DEPTH_FORMAT)))
}

fn mat(m: Mat4) -> [[f32; 4]; 4] {
    m.to_cols_array_2d()
}

impl SceneRenderer {
    /// Builds the pipelines for views of colour format `format` (a surface's format, or
    /// [`OFFSCREEN_FORMAT`](super::OFFSCREEN_FORMAT)). Uses 4× MSAA when the adapter allows it for
    /// `format`. A non-sRGB `format` (as egui wants) gets sRGB encoding in the shader instead.
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat, style: Style) -> Self {
        Self::with_samples(gpu, format, style, MSAA_SAMPLES)
    }

    /// Like [`new`](Self::new) with `samples` per pixel (1 turns multisampling off, e.g. to trade edge
    /// quality for speed on a software adapter); falls back to 1 if the adapter cannot do `samples`.
    pub fn with_samples(gpu: &Gpu, format: wgpu::TextureFormat, style: Style, samples: u32) -> Self {
        let device = &gpu.device;
        let supported = |f: wgpu::TextureFormat| {
            samples == 1 || gpu.adapter.get_texture_format_features(f).flags.sample_count_supported(samples)
        };
        let sample_count = if supported(format) && supported(DEPTH_FORMAT) { samples } else { 1 };

        let uniform_entry = |dynamic: bool, size: u64| wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: dynamic,
                min_binding_size: NonZeroU64::new(size),
            },
            count: None,
        };
        let camera_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("camera"),
            entries: &[uniform_entry(false, std::mem::size_of::<CameraUniform>() as u64)],
        });
        let object_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("object"),
            entries: &[uniform_entry(true, OBJECT_SIZE)],
        });
        let scene_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&camera_layout), Some(&object_layout)],
            immediate_size: 0,
        });
        let background_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("background"),
            bind_group_layouts: &[Some(&camera_layout)],
            immediate_size: 0,
        });
        let module = |label, source: &str| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            })
        };
        let mesh_module = module("mesh.wgsl", MESH_WGSL);
        let lines_module = module("lines.wgsl", LINES_WGSL);
        let background_module = module("background.wgsl", BACKGROUND_WGSL);

        let vec3_attr = |location| {
            [wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 0,
                shader_location: location,
            }]
        };
        let pos_attr = vec3_attr(0);
        let nrm_attr = vec3_attr(1);
        let mesh_buffers = [
            Some(wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &pos_attr,
            }),
            Some(wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &nrm_attr,
            }),
        ];
        let segment_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
        let line_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: 24,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &segment_attrs,
        })];
        let depth = |write: bool, compare| {
            Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(write),
                depth_compare: Some(compare),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            })
        };
        let targets =
            [Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })];
        let pipeline = |label: &str,
                        layout: &wgpu::PipelineLayout,
                        module: &wgpu::ShaderModule,
                        buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                        depth_stencil: Option<wgpu::DepthStencilState>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil,
                multisample: wgpu::MultisampleState { count: sample_count, ..Default::default() },
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let mesh_pipeline = pipeline(
            "mesh",
            &scene_layout,
            &mesh_module,
            &mesh_buffers,
            depth(true, wgpu::CompareFunction::Less),
        );
        let line_pipeline = pipeline(
            "lines",
            &scene_layout,
            &lines_module,
            &line_buffers,
            depth(true, wgpu::CompareFunction::LessEqual),
        );
        let overlay_line_pipeline = pipeline(
            "lines overlay",
            &scene_layout,
            &lines_module,
            &line_buffers,
            depth(false, wgpu::CompareFunction::Always),
        );
        let background_pipeline = pipeline(
            "background",
            &background_layout,
            &background_module,
            &[],
            // Drawn after the opaque scene at the far plane: only pixels nothing covered are shaded.
            depth(false, wgpu::CompareFunction::LessEqual),
        );

        let object_stride =
            OBJECT_SIZE.next_multiple_of(u64::from(device.limits().min_uniform_buffer_offset_alignment));
        let objects = GrowBuffer::new(device, "objects", wgpu::BufferUsages::UNIFORM, object_stride * 8);
        let object_bind_group = Self::object_bind_group(device, &object_layout, &objects.buffer);

        let parts = Part::ALL
            .iter()
            .map(|&part| {
                let m = mesh::part_mesh(part);
                let buffer = |label, contents: &[u8], usage| {
                    let b = GrowBuffer::new(device, label, usage, contents.len() as u64);
                    gpu.queue.write_buffer(&b.buffer, 0, contents);
                    b.buffer
                };
                PartGpu {
                    positions: buffer(
                        "part positions",
                        bytemuck::cast_slice(&m.positions),
                        wgpu::BufferUsages::VERTEX,
                    ),
                    normals: buffer(
                        "part normals",
                        bytemuck::cast_slice(&m.normals),
                        wgpu::BufferUsages::VERTEX,
                    ),
                    indices: buffer(
                        "part indices",
                        bytemuck::cast_slice(&m.indices),
                        wgpu::BufferUsages::INDEX,
                    ),
                    index_count: m.indices.len() as u32,
                }
            })
            .collect();

        Self {
            format,
            sample_count,
            style,
            camera_layout,
            mesh_pipeline,
            line_pipeline,
            overlay_line_pipeline,
            background_pipeline,
            object_layout,
            objects,
            object_bind_group,
            object_stride,
            object_scratch: Vec::new(),
            layers: Vec::new(),
            parts,
            instrument: [None; 2],
            fibres: GrowBuffer::new(device, "fibres", wgpu::BufferUsages::VERTEX, 24 * 1024),
            fibre_count: 0,
            cut: GrowBuffer::new(device, "cut path", wgpu::BufferUsages::VERTEX, 24 * 256),
            cut_count: 0,
            cut_scratch: Vec::new(),
            stats: UploadStats::default(),
        }
    }

    fn object_bind_group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        buffer: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("objects"),
            layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer,
                    offset: 0,
                    size: NonZeroU64::new(OBJECT_SIZE),
                }),
            }],
        })
    }

    /// Samples per pixel actually used (4, or 1 if the adapter cannot multisample the format).
    pub fn sample_count(&self) -> u32 {
        self.sample_count
    }

    /// The colour format the pipelines were built for.
    pub fn format(&self) -> wgpu::TextureFormat {
        self.format
    }

    /// Targets and camera uniform for one view of `width` × `height` pixels.
    pub fn create_view(&self, gpu: &Gpu, width: u32, height: u32) -> Result<SceneView, RenderError> {
        let (msaa, depth) = create_targets(gpu, self.format, self.sample_count, width, height)?;
        let camera_buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera"),
            size: std::mem::size_of::<CameraUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let camera_bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("camera"),
            layout: &self.camera_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: camera_buffer.as_entire_binding() }],
        });
        Ok(SceneView {
            width,
            height,
            format: self.format,
            sample_count: self.sample_count,
            msaa,
            depth,
            camera_buffer,
            camera_bind_group,
        })
    }

    /// Upload counters since creation.
    pub fn stats(&self) -> UploadStats {
        self.stats
    }

    /// Total triangles drawn for the tissue layers at the last [`update`](Self::update).
    pub fn layer_triangles(&self) -> u64 {
        self.layers.iter().map(|l| u64::from(l.index_count / 3)).sum()
    }

    /// Uploads a snapshot. Vertex data is rewritten in place; index buffers are rebuilt only when a
    /// layer's `topology_version` changes (or the layer is new); buffers are reallocated only on growth.
    pub fn update(&mut self, gpu: &Gpu, snapshot: &Snapshot) -> Result<(), RenderError> {
        let device = &gpu.device;
        let mut grown = 0u64;
        self.layers.truncate(snapshot.layers.len());
        while self.layers.len() < snapshot.layers.len() {
            let n = snapshot.layers[self.layers.len()].positions.len() as u64;
            self.layers.push(LayerGpu {
                positions: GrowBuffer::new(device, "layer positions", wgpu::BufferUsages::VERTEX, n * 12),
                normals: GrowBuffer::new(device, "layer normals", wgpu::BufferUsages::VERTEX, n * 12),
                indices: GrowBuffer::new(device, "layer indices", wgpu::BufferUsages::INDEX, n * 24),
                index_count: 0,
                vertex_count: 0,
                max_index: 0,
                topology_version: None,
            });
        }
        for (i, (layer, gpu_layer)) in snapshot.layers.iter().zip(self.layers.iter_mut()).enumerate() {
            if layer.normals.len() != layer.positions.len() {
                return Err(RenderError::InvalidSnapshot {
                    layer: i,
                    what: format!("{} normals for {} positions", layer.normals.len(), layer.positions.len()),
                });
            }
            let vertex_count = layer.positions.len() as u32;
            if gpu_layer.topology_version != Some(layer.topology_version) {
                let max_index = layer.triangles.iter().flatten().copied().max().unwrap_or(0);
                if !layer.triangles.is_empty() && max_index >= vertex_count {
                    return Err(RenderError::InvalidSnapshot {
                        layer: i,
                        what: format!("index {max_index} out of range for {vertex_count} vertices"),
                    });
                }
                grown += u64::from(gpu_layer.indices.write(gpu, bytemuck::cast_slice(&layer.triangles)));
                self.stats.index_rebuilds += 1;
                gpu_layer.index_count = layer.triangles.len() as u32 * 3;
                gpu_layer.max_index = max_index;
                gpu_layer.topology_version = Some(layer.topology_version);
            } else if gpu_layer.index_count > 0 && gpu_layer.max_index >= vertex_count {
                return Err(RenderError::InvalidSnapshot {
                    layer: i,
                    what: format!(
                        "vertex count fell to {vertex_count} without a topology_version bump (index {})",
                        gpu_layer.max_index
                    ),
                });
            }
            grown += u64::from(gpu_layer.positions.write(gpu, bytemuck::cast_slice(&layer.positions)));
            grown += u64::from(gpu_layer.normals.write(gpu, bytemuck::cast_slice(&layer.normals)));
            gpu_layer.vertex_count = vertex_count;
        }

        grown += u64::from(self.fibres.write(gpu, bytemuck::cast_slice(&snapshot.fibres)));
        self.fibre_count = snapshot.fibres.len() as u32;
        self.cut_scratch.clear();
        self.cut_scratch.extend(snapshot.cut_path.windows(2).map(|w| [w[0], w[1]]));
        grown += u64::from(self.cut.write(gpu, bytemuck::cast_slice(&self.cut_scratch)));
        self.cut_count = self.cut_scratch.len() as u32;

        // Object uniforms: one slot per layer, then two instrument parts, fibres, cut path.
        let n = snapshot.layers.len();
        let slots = n + 4;
        let stride = self.object_stride as usize;
        let mut scratch = std::mem::take(&mut self.object_scratch);
        scratch.clear();
        scratch.resize(slots * stride, 0);
        let mut put = |slot: usize, object: ObjectUniform| {
            scratch[slot * stride..slot * stride + OBJECT_SIZE as usize]
                .copy_from_slice(bytemuck::bytes_of(&object));
        };
        let tissue = |color: [f32; 4]| ObjectUniform {
            model: mat(Mat4::IDENTITY),
            color,
            params: [0.18, 24.0, 0.0, 0.0],
        };
        for (i, layer) in snapshot.layers.iter().enumerate() {
            put(i, tissue(layer.color));
        }
        self.instrument = [None; 2];
        if let Some(pose) = &snapshot.instrument {
            for (k, part) in mesh::instrument_parts(pose).into_iter().enumerate() {
                let Some((part, model)) = part else { continue };
                let color = if part == Part::ScalpelHandle {
                    self.style.handle_color
                } else {
                    self.style.steel_color
                };
                put(
                    n + k,
                    ObjectUniform {
                        model: mat(model),
                        color: Vec3::from(color).extend(1.0).into(),
                        params: [0.8, 60.0, 0.0, 0.0],
                    },
                );
                self.instrument[k] = Some(part);
            }
        }
        let line = |color: [f32; 3], width: f32| ObjectUniform {
            model: mat(Mat4::IDENTITY),
            color: Vec3::from(color).extend(1.0).into(),
            params: [0.0, 0.0, width, 0.0],
        };
        put(n + 2, line(self.style.fibre_color, self.style.fibre_width_px));
        put(n + 3, line(self.style.cut_color, self.style.cut_width_px));
        let grew = self.objects.write(gpu, &scratch);
        self.object_scratch = scratch;
        self.stats.reallocations += grown + u64::from(grew);
        self.stats.updates += 1;
        if grew {
            self.object_bind_group =
                Self::object_bind_group(device, &self.object_layout, &self.objects.buffer);
        }
        Ok(())
    }

    /// Records the scene as of the last [`update`](Self::update) into `target` (a view of the same size
    /// and format as `view`), seen through `camera`. Writes the view's camera uniform on the queue, so
    /// submit `encoder` before rendering the same view with another camera.
    pub fn render(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        view: &SceneView,
        target: &wgpu::TextureView,
        camera: &OrbitCamera,
    ) {
        let full = [0.0, 0.0, view.width as f32, view.height as f32];
        self.render_in(gpu, encoder, view, target, camera, full);
    }

    /// Like [`render`](Self::render), but draws only into `rect` = `[x, y, width, height]` (pixels, origin
    /// top left) of the target, e.g. the central area between UI panels; the camera's aspect is the
    /// rect's. The whole target is cleared first: draw panels afterwards. Picking rays for this view
    /// take the cursor relative to the rect's corner and the rect's size.
    pub fn render_in(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        view: &SceneView,
        target: &wgpu::TextureView,
        camera: &OrbitCamera,
        rect: [f32; 4],
    ) {
        let (vw, vh) = (view.width as f32, view.height as f32);
        let x = rect[0].clamp(0.0, vw - 1.0);
        let y = rect[1].clamp(0.0, vh - 1.0);
        let w = rect[2].clamp(1.0, vw - x);
        let h = rect[3].clamp(1.0, vh - y);
        let (forward, right, up) = camera.basis();
        let light = (-forward + 0.45 * up - 0.3 * right).normalize();
        // Line widths are given for an 800-pixel-tall view; the shader takes pixels of this view.
        let line_scale = (h / 800.0).max(0.5);
        let uniform = CameraUniform {
            view_proj: mat(camera.view_proj(w / h)),
            eye: camera.eye().extend(1.0).into(),
            light: light.extend(0.0).into(),
            viewport: [w, h, if self.format.is_srgb() { 0.0 } else { 1.0 }, line_scale],
        };
        gpu.queue.write_buffer(&view.camera_buffer, 0, bytemuck::bytes_of(&uniform));

        let (attachment, resolve) = match &view.msaa {
            Some(msaa) => (msaa, Some(target)),
            None => (target, None),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: attachment,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: if resolve.is_some() { wgpu::StoreOp::Discard } else { wgpu::StoreOp::Store },
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_viewport(x, y, w, h, 0.0, 1.0);
        pass.set_bind_group(0, &view.camera_bind_group, &[]);

        let n = self.layers.len();
        let offset = |slot: usize| (slot as u64 * self.object_stride) as u32;
        pass.set_pipeline(&self.mesh_pipeline);
        for (i, layer) in self.layers.iter().enumerate() {
            if layer.index_count == 0 || layer.vertex_count == 0 {
                continue;
            }
            pass.set_bind_group(1, &self.object_bind_group, &[offset(i)]);
            pass.set_vertex_buffer(0, layer.positions.buffer.slice(..u64::from(layer.vertex_count) * 12));
            pass.set_vertex_buffer(1, layer.normals.buffer.slice(..u64::from(layer.vertex_count) * 12));
            pass.set_index_buffer(layer.indices.buffer.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..layer.index_count, 0, 0..1);
        }
        for (k, part) in self.instrument.iter().enumerate() {
            let Some(part) = part else { continue };
            let Some(index) = Part::ALL.iter().position(|p| p == part) else { continue };
            let Some(gpu_part) = self.parts.get(index) else { continue };
            pass.set_bind_group(1, &self.object_bind_group, &[offset(n + k)]);
            pass.set_vertex_buffer(0, gpu_part.positions.slice(..));
            pass.set_vertex_buffer(1, gpu_part.normals.slice(..));
            pass.set_index_buffer(gpu_part.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..gpu_part.index_count, 0, 0..1);
        }
        if self.fibre_count > 0 {
            pass.set_pipeline(&self.line_pipeline);
            pass.set_bind_group(1, &self.object_bind_group, &[offset(n + 2)]);
            pass.set_vertex_buffer(0, self.fibres.buffer.slice(..u64::from(self.fibre_count) * 24));
            pass.draw(0..6, 0..self.fibre_count);
        }
        // The background last, depth-tested at the far plane, so covered pixels cost nothing (a software
        // rasteriser pays for every shaded fragment).
        pass.set_pipeline(&self.background_pipeline);
        pass.draw(0..3, 0..1);
        if self.cut_count > 0 {
            pass.set_pipeline(&self.overlay_line_pipeline);
            pass.set_bind_group(1, &self.object_bind_group, &[offset(n + 3)]);
            pass.set_vertex_buffer(0, self.cut.buffer.slice(..u64::from(self.cut_count) * 24));
            pass.draw(0..6, 0..self.cut_count);
        }
    }
}

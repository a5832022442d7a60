//! The scene pipelines and the GPU copies of a snapshot: layers (textured, with their cut edges as
//! walls of the layer's thickness), fibres, broken-fibre stubs and cut marks, instruments (the one in
//! hand and forceps left clamped), the instruments' shadows, the exercise's regions and planned
//! incision, the cut path.
//!
//! [`SceneRenderer::update`] uploads a [`Snapshot`] into buffers it keeps between frames (positions and
//! normals every frame with `write_buffer`; index buffers, surface coordinates and open edges only when
//! a layer's `topology_version` changes; new buffers only when something grows). [`SceneRenderer::render`] records one pass into a
//! [`SceneView`], which owns what differs per window or camera: the multisampled colour and depth
//! targets and the camera uniform.

use std::num::NonZeroU64;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use super::camera::OrbitCamera;
use super::geometry::{self, LineInstance, SurfacePiece};
use super::mesh::{self, Part};
use super::texture::{TEXTURE_SIZE, TEXTURE_TILE_M, pattern_texels, tissue_texels, vessel_color};
use super::{Gpu, RenderError};
use crate::snapshot::{InstrumentKind, InstrumentPose, RegionKind, RegionShape, Snapshot, SurfacePattern};

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
    /// Marks where fibres were cut (drawn over everything, so they show through the upper layer).
    pub mark_color: [f32; 3],
    /// Mark diameter in pixels at a 800-pixel-tall view.
    pub mark_width_px: f32,
    /// The planned incision's dashed marker line on the upper layer.
    pub incision_color: [f32; 3],
    /// Marker line width in pixels at a 800-pixel-tall view.
    pub incision_width_px: f32,
    /// Draw the exercise's target and forbidden regions and its planned incision on the tissue.
    pub show_regions: bool,
    /// Draw the instruments' shadows.
    pub shadows: bool,
    /// Draw the connective fibres, their stubs and the cut marks.
    pub show_fibres: bool,
}

impl Default for Style {
    fn default() -> Self {
        Self {
            fibre_color: [0.93, 0.84, 0.66],
            fibre_width_px: 2.5,
            cut_color: [0.1, 0.95, 0.35],
            cut_width_px: 4.0,
            steel_color: [0.7, 0.73, 0.78],
            handle_color: [0.5, 0.53, 0.58],
            mark_color: [1.0, 0.78, 0.1],
            mark_width_px: 4.5,
            incision_color: [0.3, 0.13, 0.55],
            incision_width_px: 3.5,
            show_regions: true,
            shadows: true,
            show_fibres: true,
        }
    }
}

/// Direction towards the overhead lamp that casts the instruments' shadows: above, a little to −X and
/// to −Z (the far side from the trainee's usual eye), so a shadow falls towards the viewer and to the
/// right, below the shaft on the screen rather than hidden behind it.
const LAMP: [f32; 3] = [-0.3, 1.0, -0.45];
/// Strength of the shadows (share of the lamp's light they take away).
const SHADOW_STRENGTH: f32 = 0.85;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct CameraUniform {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light: [f32; 4],
    viewport: [f32; 4],
    scene: SceneUniform,
}

/// The part of the camera uniform that comes from the snapshot, the same for every view.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct SceneUniform {
    lamp: [f32; 4],
    casters: [[f32; 4]; 4],
    regions: [[f32; 4]; 4],
    region_kinds: [f32; 4],
}

/// The planned incision's dashes: one every this many surface fractions along the line, drawn for
/// the last [`INCISION_DUTY`] of each.
const INCISION_PERIOD: f32 = 1.0 / 45.0;
const INCISION_DUTY: f32 = 0.55;
/// How far above the upper layer's surface (along its normal, metres) the incision's marker is drawn,
/// so that the depth test keeps it on the surface's outer side, also where the quad of the line tilts
/// away from the surface.
const INCISION_LIFT_M: f32 = 0.0002;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ObjectUniform {
    model: [[f32; 4]; 4],
    color: [f32; 4],
    params: [f32; 4],
    extra: [f32; 4],
    detail: [f32; 4],
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
    /// Data larger than the device's largest buffer is not written (logged instead): scenes are
    /// validated to stay under it, so this is a backstop, never a panic.
    fn write(&mut self, gpu: &Gpu, data: &[u8]) -> bool {
        let len = data.len() as u64;
        let max = gpu.device.limits().max_buffer_size;
        if len > max {
            log::error!(
                "{}: {len} bytes, more than the device's largest buffer ({max} bytes); not drawn",
                self.label
            );
            return false;
        }
        let grew = len > self.capacity;
        if grew {
            let size = len.max(self.capacity + self.capacity / 2).min(max);
            *self = Self::new(&gpu.device, self.label, self.usage, size);
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
    uv: GrowBuffer,
    indices: GrowBuffer,
    index_count: u32,
    vertex_count: u32,
    /// Largest index in the current index buffer (checked against the vertex count every frame).
    max_index: u32,
    topology_version: Option<u64>,
    /// Open edges (cuts), rebuilt with the index buffer.
    edges: Vec<[u32; 3]>,
    wall_positions: GrowBuffer,
    wall_normals: GrowBuffer,
    wall_vertex_count: u32,
    /// Which of the renderer's pattern textures the layer is drawn with.
    pattern: usize,
}

#[derive(Debug)]
struct PartGpu {
    positions: wgpu::Buffer,
    normals: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
}

/// Line instances of one kind (fibres, stubs, marks, the cut path) on the GPU.
#[derive(Debug)]
struct LinesGpu {
    buffer: GrowBuffer,
    count: u32,
    scratch: Vec<LineInstance>,
}

impl LinesGpu {
    fn new(device: &wgpu::Device, label: &'static str) -> Self {
        let bytes = std::mem::size_of::<LineInstance>() as u64 * 256;
        Self {
            buffer: GrowBuffer::new(device, label, wgpu::BufferUsages::VERTEX, bytes),
            count: 0,
            scratch: Vec::new(),
        }
    }

    /// Uploads the scratch instances; returns whether the buffer grew.
    fn upload(&mut self, gpu: &Gpu) -> bool {
        self.count = self.scratch.len() as u32;
        self.buffer.write(gpu, bytemuck::cast_slice(&self.scratch))
    }
}

/// Instrument parts drawn at most: two for the instrument in hand, two for clamped forceps.
const MAX_PARTS: usize = 4;

/// Pipelines and the GPU-side copy of the latest snapshot. One per device; shared by all views.
#[derive(Debug)]
pub struct SceneRenderer {
    format: wgpu::TextureFormat,
    sample_count: u32,
    style: Style,
    camera_layout: wgpu::BindGroupLayout,
    tissue_pipeline: wgpu::RenderPipeline,
    solid_pipeline: wgpu::RenderPipeline,
    line_pipeline: wgpu::RenderPipeline,
    overlay_line_pipeline: wgpu::RenderPipeline,
    background_pipeline: wgpu::RenderPipeline,
    object_layout: wgpu::BindGroupLayout,
    objects: GrowBuffer,
    object_bind_group: wgpu::BindGroup,
    object_stride: u64,
    object_scratch: Vec<u8>,
    /// One per [`SurfacePattern`], in [`pattern_index`] order.
    texture_bind_groups: [wgpu::BindGroup; 3],
    layers: Vec<LayerGpu>,
    parts: Vec<PartGpu>,
    instrument: [Option<Part>; MAX_PARTS],
    fibres: LinesGpu,
    stubs: LinesGpu,
    marks: LinesGpu,
    cut: LinesGpu,
    /// The planned incision's dashes, its pieces over the upper layer's triangles, and what they were
    /// found for (the layer's topology version, vertex and triangle counts, and the line).
    marker: LinesGpu,
    incision_pieces: Vec<SurfacePiece>,
    incision_key: Option<(u64, usize, usize)>,
    incision_line: Vec<[f32; 2]>,
    edge_scratch: Vec<(u64, u32)>,
    /// The triangles a layer is drawn with (see `geometry::drawn_triangles`), and that function's scratch.
    drawn_scratch: Vec<[u32; 3]>,
    quad_scratch: Vec<u8>,
    wall_scratch: (Vec<[f32; 3]>, Vec<[f32; 3]>),
    scene: SceneUniform,
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

/// A shadow caster for an instrument pose: a capsule from just above the tip up the shaft.
fn caster(pose: &InstrumentPose) -> [[f32; 4]; 2] {
    let axis = Vec3::from(pose.axis).normalize_or(Vec3::Y);
    let tip = Vec3::from(pose.tip);
    let radius = match pose.kind {
        InstrumentKind::Forceps => 0.0022,
        InstrumentKind::Scalpel => 0.0025,
        InstrumentKind::Probe => 0.0012,
    };
    [(tip + axis * 0.001).extend(radius).into(), (tip + axis * 0.11).extend(1.0).into()]
}

/// The colour of a layer's cut edge: the layer's colour, darker and redder (raw, moist tissue).
fn wall_color(c: [f32; 4]) -> [f32; 4] {
    [c[0] * 0.8, c[1] * 0.45, c[2] * 0.42, 1.0]
}

/// Index of a pattern's texture in [`SceneRenderer`]'s bind groups.
fn pattern_index(pattern: SurfacePattern) -> usize {
    match pattern {
        SurfacePattern::Grain => 0,
        SurfacePattern::Vessels => 1,
        SurfacePattern::Plain => 2,
    }
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
        let texture_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tissue texture"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let mesh_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("meshes"),
            bind_group_layouts: &[Some(&camera_layout), Some(&object_layout), Some(&texture_layout)],
            immediate_size: 0,
        });
        let line_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lines"),
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

        let attr =
            |location, format| [wgpu::VertexAttribute { format, offset: 0, shader_location: location }];
        let pos_attr = attr(0, wgpu::VertexFormat::Float32x3);
        let nrm_attr = attr(1, wgpu::VertexFormat::Float32x3);
        let uv_attr = attr(2, wgpu::VertexFormat::Float32x2);
        let per_vertex = |stride, attributes| {
            Some(wgpu::VertexBufferLayout {
                array_stride: stride,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes,
            })
        };
        let tissue_buffers =
            [per_vertex(12, &pos_attr[..]), per_vertex(12, &nrm_attr[..]), per_vertex(8, &uv_attr[..])];
        let solid_buffers = [per_vertex(12, &pos_attr[..]), per_vertex(12, &nrm_attr[..])];
        let segment_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32];
        let line_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<LineInstance>() as u64,
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
        let opaque =
            [Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })];
        let blended = [Some(wgpu::ColorTargetState {
            format,
            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let pipeline = |label: &str,
                        layout: &wgpu::PipelineLayout,
                        module: &wgpu::ShaderModule,
                        entry: (&str, &str),
                        buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                        depth_stencil: Option<wgpu::DepthStencilState>,
                        targets: &[Option<wgpu::ColorTargetState>]| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some(entry.0),
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
                    entry_point: Some(entry.1),
                    compilation_options: Default::default(),
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let less = wgpu::CompareFunction::Less;
        let tissue_pipeline = pipeline(
            "tissue",
            &mesh_layout,
            &mesh_module,
            ("vs_tissue", "fs_tissue"),
            &tissue_buffers,
            depth(true, less),
            &opaque,
        );
        let solid_pipeline = pipeline(
            "solid",
            &mesh_layout,
            &mesh_module,
            ("vs_solid", "fs_solid"),
            &solid_buffers,
            depth(true, less),
            &opaque,
        );
        let line_pipeline = pipeline(
            "lines",
            &line_layout,
            &lines_module,
            ("vs_main", "fs_main"),
            &line_buffers,
            depth(true, wgpu::CompareFunction::LessEqual),
            &opaque,
        );
        let overlay_line_pipeline = pipeline(
            "lines overlay",
            &line_layout,
            &lines_module,
            ("vs_main", "fs_overlay"),
            &line_buffers,
            depth(false, wgpu::CompareFunction::Always),
            &blended,
        );
        let background_pipeline = pipeline(
            "background",
            &background_layout,
            &background_module,
            ("vs_main", "fs_main"),
            &[],
            // Drawn after the opaque scene at the far plane: only pixels nothing covered are shaded.
            depth(false, wgpu::CompareFunction::LessEqual),
            &opaque,
        );

        let object_stride =
            OBJECT_SIZE.next_multiple_of(u64::from(device.limits().min_uniform_buffer_offset_alignment));
        let objects = GrowBuffer::new(device, "objects", wgpu::BufferUsages::UNIFORM, object_stride * 16);
        let object_bind_group = Self::object_bind_group(device, &object_layout, &objects.buffer);
        let texels = tissue_texels();
        let texture_bind_groups = [SurfacePattern::Grain, SurfacePattern::Vessels, SurfacePattern::Plain]
            .map(|pattern| Self::tissue_texture(gpu, &texture_layout, &pattern_texels(&texels, pattern)));

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
            tissue_pipeline,
            solid_pipeline,
            line_pipeline,
            overlay_line_pipeline,
            background_pipeline,
            object_layout,
            objects,
            object_bind_group,
            object_stride,
            object_scratch: Vec::new(),
            texture_bind_groups,
            layers: Vec::new(),
            parts,
            instrument: [None; MAX_PARTS],
            fibres: LinesGpu::new(device, "fibres"),
            stubs: LinesGpu::new(device, "fibre stubs"),
            marks: LinesGpu::new(device, "cut marks"),
            cut: LinesGpu::new(device, "cut path"),
            marker: LinesGpu::new(device, "planned incision"),
            incision_pieces: Vec::new(),
            incision_key: None,
            incision_line: Vec::new(),
            edge_scratch: Vec::new(),
            drawn_scratch: Vec::new(),
            quad_scratch: Vec::new(),
            wall_scratch: (Vec::new(), Vec::new()),
            scene: SceneUniform::default(),
            stats: UploadStats::default(),
        }
    }

    /// A pattern's texture (made once on the CPU, see [`pattern_texels`]) and its repeating sampler.
    fn tissue_texture(gpu: &Gpu, layout: &wgpu::BindGroupLayout, texels: &[[u8; 4]]) -> wgpu::BindGroup {
        let size = wgpu::Extent3d { width: TEXTURE_SIZE, height: TEXTURE_SIZE, depth_or_array_layers: 1 };
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("tissue texture"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(TEXTURE_SIZE * 4),
                rows_per_image: Some(TEXTURE_SIZE),
            },
            size,
        );
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("tissue texture"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            // Nearest texels: at the usual zoom a texel is about a pixel, and a software rasteriser
            // fetches one texel instead of four.
            mag_filter: wgpu::FilterMode::Nearest,
            min_filter: wgpu::FilterMode::Nearest,
            ..Default::default()
        });
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tissue texture"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) },
            ],
        })
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

    /// Colours, sizes and what is shown.
    pub fn style(&self) -> &Style {
        &self.style
    }

    /// Changes colours, sizes and what is shown (e.g. the regions toggled off); takes effect at the next
    /// [`update`](Self::update).
    pub fn set_style(&mut self, style: Style) {
        self.style = style;
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

    /// Uploads a snapshot. Vertex data is rewritten in place; index buffers, surface coordinates and
    /// open edges are rebuilt only when a layer's `topology_version` changes (or the layer is new);
    /// buffers are reallocated only on growth.
    pub fn update(&mut self, gpu: &Gpu, snapshot: &Snapshot) -> Result<(), RenderError> {
        let device = &gpu.device;
        let mut grown = 0u64;
        self.layers.truncate(snapshot.layers.len());
        while self.layers.len() < snapshot.layers.len() {
            let n = snapshot.layers[self.layers.len()].positions.len() as u64;
            let vertex = wgpu::BufferUsages::VERTEX;
            self.layers.push(LayerGpu {
                positions: GrowBuffer::new(device, "layer positions", vertex, n * 12),
                normals: GrowBuffer::new(device, "layer normals", vertex, n * 12),
                uv: GrowBuffer::new(device, "layer uv", vertex, n * 8),
                indices: GrowBuffer::new(device, "layer indices", wgpu::BufferUsages::INDEX, n * 24),
                index_count: 0,
                vertex_count: 0,
                max_index: 0,
                topology_version: None,
                edges: Vec::new(),
                wall_positions: GrowBuffer::new(device, "wall positions", vertex, 12 * 6 * 64),
                wall_normals: GrowBuffer::new(device, "wall normals", vertex, 12 * 6 * 64),
                wall_vertex_count: 0,
                pattern: 0,
            });
        }
        for (i, (layer, gpu_layer)) in snapshot.layers.iter().zip(self.layers.iter_mut()).enumerate() {
            if layer.normals.len() != layer.positions.len() {
                return Err(RenderError::InvalidSnapshot {
                    layer: i,
                    what: format!("{} normals for {} positions", layer.normals.len(), layer.positions.len()),
                });
            }
            if !layer.uv.is_empty() && layer.uv.len() != layer.positions.len() {
                return Err(RenderError::InvalidSnapshot {
                    layer: i,
                    what: format!(
                        "{} surface coordinates for {} positions",
                        layer.uv.len(),
                        layer.positions.len()
                    ),
                });
            }
            let vertex_count = layer.positions.len() as u32;
            if gpu_layer.topology_version != Some(layer.topology_version)
                || gpu_layer.vertex_count != vertex_count
            {
                let max_index = layer.triangles.iter().flatten().copied().max().unwrap_or(0);
                if !layer.triangles.is_empty() && max_index >= vertex_count {
                    return Err(RenderError::InvalidSnapshot {
                        layer: i,
                        what: format!("index {max_index} out of range for {vertex_count} vertices"),
                    });
                }
                if gpu_layer.topology_version != Some(layer.topology_version) {
                    // A grid finer than the drawn mesh's pitch is drawn in cells of several quads where
                    // nothing is cut (the frame's triangles stay about those of a 64 × 48 sheet).
                    let drawn = &mut self.drawn_scratch;
                    match layer.grid {
                        Some(grid) => {
                            let step = geometry::cell_quads(grid, layer.uv_size, geometry::SURFACE_PITCH_M);
                            geometry::drawn_triangles(layer, grid, step, &mut self.quad_scratch, drawn);
                        }
                        None => drawn.clone_from(&layer.triangles),
                    }
                    grown += u64::from(gpu_layer.indices.write(gpu, bytemuck::cast_slice(drawn)));
                    self.stats.index_rebuilds += 1;
                    gpu_layer.index_count = drawn.len() as u32 * 3;
                    gpu_layer.max_index = max_index;
                    gpu_layer.topology_version = Some(layer.topology_version);
                    geometry::open_edges(layer, &mut self.edge_scratch, &mut gpu_layer.edges);
                }
                // Surface coordinates change only with the vertices (none given: all zero).
                if layer.uv.is_empty() {
                    let zeros = vec![[0.0f32; 2]; layer.positions.len()];
                    grown += u64::from(gpu_layer.uv.write(gpu, bytemuck::cast_slice(&zeros)));
                } else {
                    grown += u64::from(gpu_layer.uv.write(gpu, bytemuck::cast_slice(&layer.uv)));
                }
            }
            grown += u64::from(gpu_layer.positions.write(gpu, bytemuck::cast_slice(&layer.positions)));
            grown += u64::from(gpu_layer.normals.write(gpu, bytemuck::cast_slice(&layer.normals)));
            gpu_layer.vertex_count = vertex_count;
            gpu_layer.pattern = pattern_index(layer.pattern);
            // Cut edges: walls down into the layer's thickness (the outer layer's inside is against
            // its normal, a deeper layer's along it, away from the layer above).
            let depth = if i == 0 { -layer.thickness } else { layer.thickness };
            let (walls, wall_normals) = &mut self.wall_scratch;
            geometry::edge_walls(layer, &gpu_layer.edges, depth, walls, wall_normals);
            grown += u64::from(gpu_layer.wall_positions.write(gpu, bytemuck::cast_slice(walls)));
            grown += u64::from(gpu_layer.wall_normals.write(gpu, bytemuck::cast_slice(wall_normals)));
            gpu_layer.wall_vertex_count = walls.len() as u32;
        }

        let show_fibres = self.style.show_fibres;
        let tear = snapshot.fibre_tear_stretch;
        // Fibres at a physical density (one per FIBRE_PITCH_M square at rest), not one per element.
        geometry::fibre_instances(
            if show_fibres { &snapshot.fibres } else { &[] },
            &snapshot.fibre_stretch,
            &snapshot.fibre_sites,
            geometry::FIBRE_PITCH_M,
            &mut self.fibres.scratch,
        );
        geometry::broken_instances(
            if show_fibres { &snapshot.broken_fibres } else { &[] },
            tear,
            geometry::FIBRE_PITCH_M,
            &mut self.stubs.scratch,
            &mut self.marks.scratch,
        );
        self.cut.scratch.clear();
        self.cut.scratch.extend(
            snapshot.cut_path.windows(2).map(|w| [w[0][0], w[0][1], w[0][2], w[1][0], w[1][1], w[1][2], 1.0]),
        );
        // The planned incision on the upper layer: clipped to its triangles when its topology or the line
        // changes, placed on the deformed surface every frame. All of its points, however many.
        self.marker.scratch.clear();
        if let Some(upper) = snapshot.layers.first()
            && self.style.show_regions
            && snapshot.incision.len() >= 2
        {
            let key = Some((upper.topology_version, upper.positions.len(), upper.triangles.len()));
            if self.incision_key != key || self.incision_line != snapshot.incision {
                geometry::surface_pieces(upper, &snapshot.incision, &mut self.incision_pieces);
                self.incision_key = key;
                self.incision_line.clone_from(&snapshot.incision);
            }
            geometry::dashed_instances(
                upper,
                &self.incision_pieces,
                INCISION_PERIOD,
                INCISION_DUTY,
                INCISION_LIFT_M,
                &mut self.marker.scratch,
            );
        }
        for lines in [&mut self.fibres, &mut self.stubs, &mut self.marks, &mut self.cut, &mut self.marker] {
            grown += u64::from(lines.upload(gpu));
        }

        // What every view's camera uniform carries from the snapshot: lamp, shadow casters, regions.
        let mut scene = SceneUniform {
            lamp: Vec3::from(LAMP)
                .normalize()
                .extend(if self.style.shadows { SHADOW_STRENGTH } else { 0.0 })
                .into(),
            ..SceneUniform::default()
        };
        for (k, pose) in snapshot.instrument.iter().chain(snapshot.clamped.iter()).take(2).enumerate() {
            let [a, b] = caster(pose);
            scene.casters[2 * k] = a;
            scene.casters[2 * k + 1] = b;
        }
        if self.style.show_regions {
            for (k, region) in snapshot.regions.iter().take(4).enumerate() {
                let forbidden = region.kind == RegionKind::Forbidden;
                let (shape, code) = match region.shape {
                    RegionShape::Rect { u, v } => ([u[0], u[1], v[0], v[1]], 1.0),
                    RegionShape::Disc { center, radius } => ([center[0], center[1], radius, 0.0], 3.0),
                };
                scene.regions[k] = shape;
                scene.region_kinds[k] = code + if forbidden { 1.0 } else { 0.0 };
            }
        }
        self.scene = scene;

        // Object uniforms: a slot per layer, one per layer's walls, then the instrument parts, fibres,
        // stubs, marks, cut path and the planned incision.
        let n = snapshot.layers.len();
        let slots = 2 * n + MAX_PARTS + 5;
        let stride = self.object_stride as usize;
        let mut scratch = std::mem::take(&mut self.object_scratch);
        scratch.clear();
        scratch.resize(slots * stride, 0);
        let mut put = |slot: usize, object: ObjectUniform| {
            scratch[slot * stride..slot * stride + OBJECT_SIZE as usize]
                .copy_from_slice(bytemuck::bytes_of(&object));
        };
        for (i, layer) in snapshot.layers.iter().enumerate() {
            let repeats = layer.uv_size.map(|s| s / TEXTURE_TILE_M);
            put(
                i,
                ObjectUniform {
                    model: mat(Mat4::IDENTITY),
                    color: layer.color,
                    params: [0.35, 0.0, 0.0, 0.0],
                    extra: [repeats[0], repeats[1], 0.0, 0.0],
                    detail: Vec3::from(vessel_color(layer.pattern)).extend(0.0).into(),
                },
            );
            put(
                n + i,
                ObjectUniform {
                    model: mat(Mat4::IDENTITY),
                    color: wall_color(layer.color),
                    params: [0.3, 40.0, 0.0, 0.0],
                    extra: [0.0; 4],
                    detail: [0.0; 4],
                },
            );
        }
        self.instrument = [None; MAX_PARTS];
        let poses = [snapshot.instrument, snapshot.clamped];
        for (h, pose) in poses.iter().enumerate() {
            let Some(pose) = pose else { continue };
            for (k, part) in mesh::instrument_parts(pose).into_iter().enumerate() {
                let Some((part, model)) = part else { continue };
                let (color, steel) = if part == Part::ScalpelHandle {
                    (self.style.handle_color, 0.0)
                } else {
                    (self.style.steel_color, 1.0)
                };
                put(
                    2 * n + 2 * h + k,
                    ObjectUniform {
                        model: mat(model),
                        color: Vec3::from(color).extend(1.0).into(),
                        params: [0.8, 60.0, steel, 0.0],
                        extra: [0.0; 4],
                        detail: [0.0; 4],
                    },
                );
                self.instrument[2 * h + k] = Some(part);
            }
        }
        let line =
            |color: [f32; 3], alpha: f32, width: f32, dots: bool, flat: bool, tear: f32| ObjectUniform {
                model: mat(Mat4::IDENTITY),
                color: Vec3::from(color).extend(alpha).into(),
                params: [f32::from(u8::from(dots)), f32::from(u8::from(flat)), width, tear],
                extra: [0.0; 4],
                detail: [0.0; 4],
            };
        let style = &self.style;
        let base = 2 * n + MAX_PARTS;
        put(base, line(style.fibre_color, 1.0, style.fibre_width_px, false, false, tear));
        put(base + 1, line(style.fibre_color, 1.0, style.fibre_width_px, false, false, tear));
        put(base + 2, line(style.mark_color, 0.85, style.mark_width_px, true, false, 0.0));
        put(base + 3, line(style.cut_color, 1.0, style.cut_width_px, false, false, 0.0));
        put(base + 4, line(style.incision_color, 1.0, style.incision_width_px, false, true, 0.0));
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
            scene: self.scene,
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
        // Group 2 must be set for the mesh layout even with no layer; each layer sets its pattern's.
        pass.set_bind_group(2, &self.texture_bind_groups[0], &[]);

        let n = self.layers.len();
        let offset = |slot: usize| (slot as u64 * self.object_stride) as u32;
        pass.set_pipeline(&self.tissue_pipeline);
        for (i, layer) in self.layers.iter().enumerate() {
            if layer.index_count == 0 || layer.vertex_count == 0 {
                continue;
            }
            pass.set_bind_group(1, &self.object_bind_group, &[offset(i)]);
            if let Some(texture) = self.texture_bind_groups.get(layer.pattern) {
                pass.set_bind_group(2, texture, &[]);
            }
            pass.set_vertex_buffer(0, layer.positions.buffer.slice(..u64::from(layer.vertex_count) * 12));
            pass.set_vertex_buffer(1, layer.normals.buffer.slice(..u64::from(layer.vertex_count) * 12));
            pass.set_vertex_buffer(2, layer.uv.buffer.slice(..u64::from(layer.vertex_count) * 8));
            pass.set_index_buffer(layer.indices.buffer.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..layer.index_count, 0, 0..1);
        }
        pass.set_pipeline(&self.solid_pipeline);
        for (i, layer) in self.layers.iter().enumerate() {
            if layer.wall_vertex_count == 0 {
                continue;
            }
            let bytes = u64::from(layer.wall_vertex_count) * 12;
            pass.set_bind_group(1, &self.object_bind_group, &[offset(n + i)]);
            pass.set_vertex_buffer(0, layer.wall_positions.buffer.slice(..bytes));
            pass.set_vertex_buffer(1, layer.wall_normals.buffer.slice(..bytes));
            pass.draw(0..layer.wall_vertex_count, 0..1);
        }
        for (k, part) in self.instrument.iter().enumerate() {
            let Some(part) = part else { continue };
            let Some(index) = Part::ALL.iter().position(|p| p == part) else { continue };
            let Some(gpu_part) = self.parts.get(index) else { continue };
            pass.set_bind_group(1, &self.object_bind_group, &[offset(2 * n + k)]);
            pass.set_vertex_buffer(0, gpu_part.positions.slice(..));
            pass.set_vertex_buffer(1, gpu_part.normals.slice(..));
            pass.set_index_buffer(gpu_part.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..gpu_part.index_count, 0, 0..1);
        }
        let base = 2 * n + MAX_PARTS;
        let instance_bytes = std::mem::size_of::<LineInstance>() as u64;
        let draw_lines = |pass: &mut wgpu::RenderPass<'_>, lines: &LinesGpu, slot: usize| {
            if lines.count > 0 {
                pass.set_bind_group(1, &self.object_bind_group, &[offset(slot)]);
                pass.set_vertex_buffer(
                    0,
                    lines.buffer.buffer.slice(..u64::from(lines.count) * instance_bytes),
                );
                pass.draw(0..6, 0..lines.count);
            }
        };
        pass.set_pipeline(&self.line_pipeline);
        draw_lines(&mut pass, &self.fibres, base);
        draw_lines(&mut pass, &self.stubs, base + 1);
        draw_lines(&mut pass, &self.marker, base + 4);
        // The background last, depth-tested at the far plane, so covered pixels cost nothing (a software
        // rasteriser pays for every shaded fragment).
        pass.set_pipeline(&self.background_pipeline);
        pass.draw(0..3, 0..1);
        pass.set_pipeline(&self.overlay_line_pipeline);
        draw_lines(&mut pass, &self.marks, base + 2);
        draw_lines(&mut pass, &self.cut, base + 3);
    }
}

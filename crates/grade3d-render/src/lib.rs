//! Offscreen depth maps of a body with wgpu — the one module of the crate
//! that touches the GPU.
//!
//! One [`GpuContext`] per process (adapter, device, queue, the two
//! pipelines) is shared by every request; [`GpuContext::render`] turns a
//! body mesh into the [`DepthMap`]s of its views. Per view, the mesh is
//! drawn twice into two `Rgba8Unorm` targets: depth packed into 24 bits
//! (RGB) and the vertex normal (`n·½ + ½`). The first pass keeps the
//! nearest surface (depth test *Less*, cleared to 1), the second the
//! farthest (*Greater*, cleared to 0) — no float blending, no float render
//! targets, no depth-texture copies, so it runs under the GL backend's
//! downlevel limits (llvmpipe) as well as on Vulkan (lavapipe, GPUs).
//! Rows of the read-back are padded to 256 bytes.
//!
//! Backend: `WGPU_BACKEND` (`gl`, `vulkan`, …) or every available one.
//! Failure modes: no adapter, device request refused, read-back failure —
//! each a [`RenderError`].
//!
//! [`Renderer`] is what the service and the CLI hold: the wgpu context on
//! a GPU, or the core's CPU rasteriser
//! ([`grade3d_core::collide::raster`]) where wgpu's only adapter is itself
//! a CPU driver (llvmpipe, lavapipe) or there is none — the same maps
//! (`tests/collide.rs` holds both to one reference) at a fraction of the
//! time (issue #15). [`RendererChoice`] overrides the choice.

use std::sync::mpsc;

use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use wgpu::util::DeviceExt;

use grade3d_core::collide::depth::{DepthMap, View, DEPTH_CODES};
use grade3d_core::collide::raster::{CpuRasteriser, RasterError, MAX_RESOLUTION};
use grade3d_core::collide::DepthRenderer;
pub use grade3d_core::collide::RenderOptions;
use grade3d_core::geom::mesh::TriMesh;

/// Why rendering failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// No adapter for the requested backends.
    #[error(
        "no graphics adapter available ({0}); install Mesa (llvmpipe for GL, lavapipe for Vulkan) or set WGPU_BACKEND"
    )]
    NoAdapter(String),
    /// The device request was refused.
    #[error("graphics device request refused: {0}")]
    Device(String),
    /// Resolution outside what the device allows.
    #[error("depth-map resolution {requested} is outside 16..={max}")]
    Resolution {
        /// Requested.
        requested: u32,
        /// Device maximum.
        max: u32,
    },
    /// Reading the maps back failed.
    #[error("depth-map read-back failed: {0}")]
    Readback(String),
}

/// What every view of one body shares: normals and the index buffer.
struct Body<'a> {
    mesh: &'a TriMesh,
    normals: &'a [DVec3],
    indices: &'a wgpu::Buffer,
    index_count: u32,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct Vertex {
    clip: [f32; 3],
    normal: [f32; 3],
}

const SHADER: &str = r#"
struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) n: vec3<f32>,
};

@vertex
fn vs(@location(0) p: vec3<f32>, @location(1) n: vec3<f32>) -> VOut {
    var o: VOut;
    o.pos = vec4<f32>(p.x, p.y, p.z, 1.0);
    o.n = n;
    return o;
}

struct FOut {
    @location(0) depth: vec4<f32>,
    @location(1) normal: vec4<f32>,
};

@fragment
fn fs(i: VOut) -> FOut {
    let d = u32(clamp(i.pos.z, 0.0, 1.0) * 16777215.0);
    var o: FOut;
    o.depth = vec4<f32>(f32((d >> 16u) & 255u), f32((d >> 8u) & 255u), f32(d & 255u), 255.0) / 255.0;
    o.normal = vec4<f32>(normalize(i.n) * 0.5 + vec3<f32>(0.5), 1.0);
    return o;
}
"#;

const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The process-wide GPU context.
#[derive(Debug)]
pub struct GpuContext {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    nearest: wgpu::RenderPipeline,
    farthest: wgpu::RenderPipeline,
    max_dimension: u32,
}

impl GpuContext {
    /// Opens an adapter (backend from `WGPU_BACKEND`, else any) and builds the pipelines.
    pub fn new() -> Result<Self, RenderError> {
        Self::with_instance(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
    }

    /// Opens an adapter of one of `backends` (ignoring `WGPU_BACKEND`).
    pub fn with_backends(backends: wgpu::Backends) -> Result<Self, RenderError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = backends;
        Self::with_instance(desc)
    }

    fn with_instance(desc: wgpu::InstanceDescriptor) -> Result<Self, RenderError> {
        Self::with_adapter(open_adapter(desc)?)
    }

    fn with_adapter(adapter: wgpu::Adapter) -> Result<Self, RenderError> {
        let info = adapter.get_info();
        let limits = wgpu::Limits::downlevel_webgl2_defaults().using_resolution(adapter.limits());
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("grade3d depth maps"),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device(e.to_string()))?;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("grade3d depth shader"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("grade3d depth pipeline layout"),
            bind_group_layouts: &[],
            immediate_size: 0,
        });
        let pipeline = |label: &str, compare: wgpu::CompareFunction| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
                    })],
                },
                primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs"),
                    compilation_options: Default::default(),
                    targets: &[
                        Some(wgpu::ColorTargetState { format: COLOR, blend: None, write_mask: wgpu::ColorWrites::ALL }),
                        Some(wgpu::ColorTargetState { format: COLOR, blend: None, write_mask: wgpu::ColorWrites::ALL }),
                    ],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let nearest = pipeline("grade3d nearest-surface pipeline", wgpu::CompareFunction::Less);
        let farthest = pipeline("grade3d farthest-surface pipeline", wgpu::CompareFunction::Greater);
        Ok(Self { device, queue, info, nearest, farthest, max_dimension: limits.max_texture_dimension_2d })
    }

    /// The adapter in use (for logs and reports).
    pub fn adapter(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// The depth maps of `mesh` for the configured views.
    ///
    /// Every pass of every view is recorded into one command buffer and
    /// submitted once: the three render targets (depth buffer, packed
    /// depth, normals) are shared by the passes, each pass's targets copied
    /// to its own read-back buffers before the next pass clears them, and
    /// the device is waited on once for all read-backs (issue #15: one
    /// submission and one wait per body instead of one per pass).
    pub fn render(&self, mesh: &TriMesh, opts: &RenderOptions) -> Result<Vec<DepthMap>, RenderError> {
        let n = opts.resolution;
        if !(16..=self.max_dimension).contains(&n) {
            return Err(RenderError::Resolution { requested: n, max: self.max_dimension });
        }
        let bb = mesh.aabb();
        let views = View::set(opts.views, bb.min, bb.max, opts.padding_mm * 1e-3);
        let normals = mesh.vertex_normals();
        let indices: Vec<u32> = mesh.triangles().iter().flat_map(|t| t.map(|v| v.0)).collect();
        let ibuf = self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grade3d body indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let body = Body { mesh, normals: &normals, indices: &ibuf, index_count: indices.len() as u32 };
        let extent = wgpu::Extent3d { width: n, height: n, depth_or_array_layers: 1 };
        let texture = |label: &str, format: wgpu::TextureFormat, usage: wgpu::TextureUsages| {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: extent,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let color_usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let targets = Targets {
            depth: texture("grade3d depth buffer", DEPTH, wgpu::TextureUsages::RENDER_ATTACHMENT),
            packed: texture("grade3d packed depth", COLOR, color_usage),
            normal: texture("grade3d normals", COLOR, color_usage),
        };
        let padded_row = (4 * n).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("grade3d depth-map encoder") });
        // per view, per pass (nearest, farthest): the packed-depth and normal read-backs
        let readbacks: Vec<[[wgpu::Buffer; 2]; 2]> =
            views.iter().map(|v| self.encode_view(&mut enc, &body, &targets, v, n, padded_row)).collect();
        self.queue.submit([enc.finish()]);
        let (tx, rx) = mpsc::channel();
        for buf in readbacks.iter().flatten().flatten() {
            let tx = tx.clone();
            buf.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                let _ = tx.send(r);
            });
        }
        self.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        let mapped: Vec<_> = rx.try_iter().collect();
        if mapped.len() != 4 * readbacks.len() {
            return Err(RenderError::Readback(format!(
                "{} of {} read-back buffers mapped after the wait",
                mapped.len(),
                4 * readbacks.len()
            )));
        }
        for r in mapped {
            r.map_err(|e| RenderError::Readback(e.to_string()))?;
        }
        views.iter().zip(&readbacks).map(|(v, bufs)| decode(v, bufs, n, padded_row)).collect()
    }

    /// Records the nearest and farthest passes of one view into `enc`, each
    /// followed by the copies of its two colour targets into new read-back
    /// buffers (returned per pass: packed depth, normals).
    fn encode_view(
        &self,
        enc: &mut wgpu::CommandEncoder,
        body: &Body<'_>,
        targets: &Targets,
        view: &View,
        n: u32,
        padded_row: u32,
    ) -> [[wgpu::Buffer; 2]; 2] {
        let vertices: Vec<Vertex> = body
            .mesh
            .positions()
            .iter()
            .zip(body.normals)
            .map(|(p, nn)| Vertex { clip: view.clip(*p), normal: nn.as_vec3().to_array() })
            .collect();
        let vbuf = self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grade3d body vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let extent = wgpu::Extent3d { width: n, height: n, depth_or_array_layers: 1 };
        let colour_views = [&targets.packed, &targets.normal].map(|t| t.create_view(&Default::default()));
        let depth_view = targets.depth.create_view(&Default::default());
        [("nearest", &self.nearest, 1.0f32), ("farthest", &self.farthest, 0.0)].map(|(pass, pipeline, clear_depth)| {
            {
                let attach = |v| {
                    Some(wgpu::RenderPassColorAttachment {
                        view: v,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })
                };
                let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(&format!("grade3d {pass} depth-map pass")),
                    color_attachments: &[attach(&colour_views[0]), attach(&colour_views[1])],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &depth_view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(clear_depth),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    ..Default::default()
                });
                rp.set_pipeline(pipeline);
                rp.set_vertex_buffer(0, vbuf.slice(..));
                rp.set_index_buffer(body.indices.slice(..), wgpu::IndexFormat::Uint32);
                rp.draw_indexed(0..body.index_count, 0, 0..1);
            }
            [(&targets.packed, "depth"), (&targets.normal, "normal")].map(|(t, what)| {
                let buf = self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&format!("grade3d {pass} {what} read-back")),
                    size: u64::from(padded_row) * u64::from(n),
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                });
                enc.copy_texture_to_buffer(
                    t.as_image_copy(),
                    wgpu::TexelCopyBufferInfo {
                        buffer: &buf,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(padded_row),
                            rows_per_image: Some(n),
                        },
                    },
                    extent,
                );
                buf
            })
        })
    }
}

impl DepthRenderer for GpuContext {
    type Error = RenderError;

    fn depth_maps(&self, mesh: &TriMesh, opts: &RenderOptions) -> Result<Vec<DepthMap>, RenderError> {
        self.render(mesh, opts)
    }
}

/// The adapter wgpu picks for `desc` (high performance first).
fn open_adapter(desc: wgpu::InstanceDescriptor) -> Result<wgpu::Adapter, RenderError> {
    let instance = wgpu::Instance::new(desc);
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..Default::default()
    }))
    .map_err(|e| RenderError::NoAdapter(e.to_string()))
}

/// Which renderer draws the depth maps ([`Renderer::new`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum RendererChoice {
    /// wgpu on a GPU; the CPU rasteriser where wgpu's adapter is a CPU
    /// driver or there is no adapter. The default.
    #[default]
    Auto,
    /// wgpu, whatever its adapter (an error without one).
    Wgpu,
    /// The CPU rasteriser.
    Cpu,
}

impl std::str::FromStr for RendererChoice {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Self::Auto),
            "wgpu" => Ok(Self::Wgpu),
            "cpu" => Ok(Self::Cpu),
            _ => Err(format!("renderer `{s}` is none of auto, wgpu, cpu")),
        }
    }
}

impl std::fmt::Display for RendererChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Auto => "auto",
            Self::Wgpu => "wgpu",
            Self::Cpu => "cpu",
        })
    }
}

/// The process's depth-map renderer (module docs).
#[derive(Debug)]
pub enum Renderer {
    /// wgpu on its adapter.
    Wgpu(Box<GpuContext>),
    /// The core's CPU rasteriser; why it was chosen (for logs and `/readyz`).
    Cpu {
        /// The reason, e.g. the CPU driver wgpu offered.
        reason: String,
    },
}

impl Renderer {
    /// The renderer `choice` asks for (module docs). Auto opens wgpu's
    /// adapter (`WGPU_BACKEND` as [`GpuContext::new`]) and asks for a
    /// device only when the adapter is not a CPU.
    ///
    /// # Errors
    /// With [`RendererChoice::Wgpu`], [`GpuContext::new`]'s; the others do not fail.
    pub fn new(choice: RendererChoice) -> Result<Self, RenderError> {
        let from_env = wgpu::InstanceDescriptor::new_without_display_handle_from_env;
        match choice {
            RendererChoice::Cpu => Ok(Self::Cpu { reason: "chosen".into() }),
            RendererChoice::Wgpu => GpuContext::new().map(|g| Self::Wgpu(Box::new(g))),
            RendererChoice::Auto => match open_adapter(from_env()) {
                Ok(a) if a.get_info().device_type == wgpu::DeviceType::Cpu => {
                    let info = a.get_info();
                    Ok(Self::Cpu {
                        reason: format!("wgpu's adapter {} ({:?}) is a CPU driver", info.name, info.backend),
                    })
                }
                Ok(a) => match GpuContext::with_adapter(a) {
                    Ok(g) => Ok(Self::Wgpu(Box::new(g))),
                    Err(e) => Ok(Self::Cpu { reason: format!("the GPU refused a device: {e}") }),
                },
                Err(e) => Ok(Self::Cpu { reason: format!("no wgpu adapter: {e}") }),
            },
        }
    }

    /// What draws the maps, for logs and `/readyz`: the adapter's name and
    /// backend, or the CPU rasteriser and why.
    pub fn describe(&self) -> String {
        match self {
            Self::Wgpu(g) => format!("{} ({:?})", g.adapter().name, g.adapter().backend),
            Self::Cpu { reason } => format!("CPU rasteriser ({reason})"),
        }
    }
}

impl DepthRenderer for Renderer {
    type Error = RenderError;

    fn depth_maps(&self, mesh: &TriMesh, opts: &RenderOptions) -> Result<Vec<DepthMap>, RenderError> {
        match self {
            Self::Wgpu(g) => g.render(mesh, opts),
            Self::Cpu { .. } => CpuRasteriser.depth_maps(mesh, opts).map_err(|e| match e {
                RasterError::Resolution { requested } => RenderError::Resolution { requested, max: MAX_RESOLUTION },
            }),
        }
    }
}

/// The render targets every pass of one body shares.
struct Targets {
    depth: wgpu::Texture,
    packed: wgpu::Texture,
    normal: wgpu::Texture,
}

/// The depth map of `view` from its mapped read-backs (per pass: packed
/// depth, normals; rows `padded_row` bytes apart): each row's covered run
/// copied as rendered ([`DepthMap::from_rows`]), and the buffers unmapped.
fn decode(view: &View, bufs: &[[wgpu::Buffer; 2]; 2], n: u32, padded_row: u32) -> Result<DepthMap, RenderError> {
    let (row, stride) = ((4 * n) as usize, padded_row as usize);
    let [[front, front_normal], [back, back_normal]] = bufs;
    let all = [front, back, front_normal, back_normal];
    let mapped = all
        .iter()
        .map(|b| b.slice(..).get_mapped_range().map_err(|e| RenderError::Readback(e.to_string())))
        .collect::<Result<Vec<_>, _>>()?;
    let image_row = |k: usize, y: usize| -> &[[u8; 4]] {
        mapped.get(k).map_or(&[], |data| bytemuck::cast_slice(&data[y * stride..y * stride + row]))
    };
    let map = DepthMap::from_rows(*view, n, n, |y| [0, 1, 2, 3].map(|k| image_row(k, y)));
    drop(mapped);
    for b in all {
        b.unmap();
    }
    Ok(map)
}

/// Distance a depth code step represents along a view, m (for tolerances).
pub fn depth_resolution(view: &View) -> f64 {
    (view.d_range[1] - view.d_range[0]) / DEPTH_CODES
}

/// The world position of a point on the nearest surface of a pixel (for tests and images).
pub fn pixel_point(map: &DepthMap, x: u32, y: u32) -> Option<DVec3> {
    let f = map.front_depth((y * map.width + x) as usize)?;
    let v = &map.view;
    let a = v.u_range[0] + (f64::from(x) + 0.5) / f64::from(map.width) * (v.u_range[1] - v.u_range[0]);
    let b = v.w_range[1] - (f64::from(y) + 0.5) / f64::from(map.height) * (v.w_range[1] - v.w_range[0]);
    Some(v.u * a + v.w * b + v.d * f)
}

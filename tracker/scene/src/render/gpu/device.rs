//! Vulkan adapter and device selection, and capture of asynchronous device errors.

use super::super::RenderError;
use std::sync::{Arc, Mutex};

/// The hint printed when no Vulkan adapter exists.
pub(super) const INSTALL_HINT: &str = "install a Vulkan driver; without a GPU, Mesa's lavapipe CPU driver \
     works (Debian/Ubuntu: apt-get install mesa-vulkan-drivers)";

/// An opened device with its queue and a record of errors reported outside error scopes.
pub(super) struct Gpu {
    pub(super) device: wgpu::Device,
    pub(super) queue: wgpu::Queue,
    /// `adapter name (driver, device type)`.
    pub(super) description: String,
    /// Whether the driver rasterises on the CPU (lavapipe).
    pub(super) on_cpu: bool,
    /// The device's limits (texture size, buffer size, uniform alignment).
    pub(super) limits: wgpu::Limits,
    /// The first uncaptured device error since the last [`Gpu::take_error`].
    errors: Arc<Mutex<Option<String>>>,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu")
            .field("adapter", &self.description)
            .finish_non_exhaustive()
    }
}

/// Ranks adapters: real GPUs first, then virtual, then CPU (lavapipe), then anything else.
fn rank(info: &wgpu::AdapterInfo) -> u8 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

impl Gpu {
    /// Opens the best Vulkan adapter (a hardware GPU if there is one, else a CPU driver such as lavapipe).
    pub(super) fn open() -> Result<Self, RenderError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
        let adapter = adapters
            .into_iter()
            .min_by_key(|a| rank(&a.get_info()))
            .ok_or_else(|| {
                RenderError::Unavailable(format!("no Vulkan adapter found: {INSTALL_HINT}"))
            })?;
        let info = adapter.get_info();
        let description = format!(
            "{} ({}, {:?})",
            info.name, info.driver_info, info.device_type
        );
        let adapter_limits = adapter.limits();
        // Ask for the adapter's texture and buffer sizes so full frames fit; everything else at the defaults.
        let limits = wgpu::Limits {
            max_texture_dimension_2d: adapter_limits.max_texture_dimension_2d,
            max_buffer_size: adapter_limits.max_buffer_size,
            max_storage_buffer_binding_size: adapter_limits.max_storage_buffer_binding_size,
            ..wgpu::Limits::downlevel_defaults()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("eventtrack6d renderer"),
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| {
            RenderError::Unavailable(format!("cannot open Vulkan device {description}: {e}"))
        })?;
        let limits = device.limits();
        let errors: Arc<Mutex<Option<String>>> = Arc::default();
        let sink = Arc::clone(&errors);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut slot) = sink.lock() {
                slot.get_or_insert_with(|| e.to_string());
            }
        }));
        Ok(Self {
            device,
            queue,
            description,
            on_cpu: info.device_type == wgpu::DeviceType::Cpu,
            limits,
            errors,
        })
    }

    /// The first device error reported since the last call, as a backend error.
    pub(super) fn take_error(&self) -> Result<(), RenderError> {
        let error = self.errors.lock().ok().and_then(|mut slot| slot.take());
        match error {
            Some(e) => Err(RenderError::Backend(format!(
                "GPU device error on {}: {e}",
                self.description
            ))),
            None => Ok(()),
        }
    }
}

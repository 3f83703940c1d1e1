//! An Open Image Denoise device: CUDA where OIDN has one for the Vulkan device caustica renders on
//! (matched by the device UUID both APIs report), else the CPU. Owns the handle and turns OIDN's
//! error state into `Result`s.

use super::ffi::{self, DeviceHandle, Oidn};
use anyhow::{anyhow, bail, Result};
use std::ffi::{c_char, CStr, CString};
use std::sync::Arc;

/// The kind of OIDN device that denoises.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceKind {
    Cpu,
    Cuda,
    Sycl,
    Hip,
    Metal,
}

impl DeviceKind {
    fn from_oidn(kind: i32) -> Option<Self> {
        Some(match kind {
            ffi::DEVICE_TYPE_CPU => DeviceKind::Cpu,
            ffi::DEVICE_TYPE_CUDA => DeviceKind::Cuda,
            ffi::DEVICE_TYPE_SYCL => DeviceKind::Sycl,
            ffi::DEVICE_TYPE_HIP => DeviceKind::Hip,
            ffi::DEVICE_TYPE_METAL => DeviceKind::Metal,
            _ => return None,
        })
    }

    pub fn label(self) -> &'static str {
        match self {
            DeviceKind::Cpu => "CPU",
            DeviceKind::Cuda => "CUDA",
            DeviceKind::Sycl => "SYCL",
            DeviceKind::Hip => "HIP",
            DeviceKind::Metal => "Metal",
        }
    }
}

/// Which OIDN device to take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceChoice {
    /// The GPU device of this Vulkan device's UUID (`None`: the Vulkan device did not say, or
    /// there is none), else the CPU: what a render on that device uses.
    SameAs(Option<[u8; ffi::UUID_SIZE]>),
    /// OIDN's first GPU device, else the CPU: for denoising files, with no Vulkan device in use.
    AnyGpu,
}

/// A committed OIDN device.
pub struct Device {
    pub(super) oidn: Arc<Oidn>,
    pub(super) handle: DeviceHandle,
    pub kind: DeviceKind,
    /// The physical device's name as OIDN reports it (a CPU's model, a GPU's name); may be empty.
    pub name: String,
    /// OIDN's version, e.g. 20501 for 2.5.1.
    pub version: i32,
}

impl Device {
    /// The device `choice` asks for where OIDN has it, else the CPU device.
    pub fn new(oidn: Arc<Oidn>, choice: DeviceChoice) -> Result<Self> {
        let physical = match choice {
            DeviceChoice::SameAs(Some(uuid)) => gpu_where(&oidn, |found| found == Some(&uuid)),
            DeviceChoice::SameAs(None) => None,
            DeviceChoice::AnyGpu => gpu_where(&oidn, |_| true),
        };
        let (handle, kind, name) = match physical {
            Some((id, kind, name)) => {
                // SAFETY: `id` is a physical device index OIDN reported (below oidnGetNumPhysicalDevices).
                (unsafe { (oidn.api.oidnNewDeviceByID)(id) }, kind, name)
            }
            None => {
                // SAFETY: a plain call with a device type of oidn.h.
                let handle = unsafe { (oidn.api.oidnNewDevice)(ffi::DEVICE_TYPE_CPU) };
                (handle, DeviceKind::Cpu, cpu_name(&oidn))
            }
        };
        if handle.is_null() {
            bail!("Open Image Denoise could not create its {} device", kind.label());
        }
        let mut device = Self { oidn, handle, kind, name, version: 0 };
        // The version first, before the device is committed: a library that exports OIDN 2's names
        // but is another major version is refused before it does any work.
        device.version = device.checked_version()?;
        // SAFETY: `handle` is a live device this struct owns.
        unsafe { (device.oidn.api.oidnCommitDevice)(device.handle) };
        device.check(&format!("starting its {} device", kind.label()))?;
        Ok(device)
    }

    /// "2.5.1".
    pub fn version_text(&self) -> String {
        version_text(self.version)
    }

    /// OIDN's version (20501 for 2.5.1), or an error where its major version is not 2.
    fn checked_version(&self) -> Result<i32> {
        let (version, major) = (self.int("version"), self.int("versionMajor"));
        if major != 2 {
            bail!(
                "it is Open Image Denoise version {}, not 2 (caustica needs {}, major version 2)",
                version_text(version),
                super::LIBRARY_NAME
            );
        }
        Ok(version)
    }

    /// Checks that `oidn` is major version 2 on a CPU device created for the purpose and never
    /// committed (creating one does no work): loading calls this, so that a wrong library fails
    /// before anything else is done.
    pub fn check_version(oidn: &Arc<Oidn>) -> Result<()> {
        // SAFETY: a plain call with a device type of oidn.h.
        let handle = unsafe { (oidn.api.oidnNewDevice)(ffi::DEVICE_TYPE_CPU) };
        if handle.is_null() {
            bail!("Open Image Denoise could not create its CPU device");
        }
        let probe = Self { oidn: oidn.clone(), handle, kind: DeviceKind::Cpu, name: String::new(), version: 0 };
        probe.checked_version().map(|_| ())
    }

    /// "CUDA (NVIDIA H100 80GB HBM3)", "CPU (AMD EPYC 9B14)".
    pub fn describe(&self) -> String {
        match self.name.is_empty() {
            true => self.kind.label().to_owned(),
            false => format!("{} ({})", self.kind.label(), self.name),
        }
    }

    fn int(&self, name: &str) -> i32 {
        let name = CString::new(name).expect("parameter names have no NUL");
        // SAFETY: `handle` is live and `name` a NUL-terminated string that outlives the call.
        unsafe { (self.oidn.api.oidnGetDeviceInt)(self.handle, name.as_ptr()) }
    }

    /// The device's pending error, if any (reading it clears it), as "what: OIDN's message".
    pub(super) fn check(&self, what: &str) -> Result<()> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: `handle` is live; OIDN writes a pointer to a NUL-terminated message it owns, valid
        // until the next call on the device, and copied below before any.
        let code = unsafe { (self.oidn.api.oidnGetDeviceError)(self.handle, &mut message) };
        if code == ffi::ERROR_NONE {
            return Ok(());
        }
        let text = match message.is_null() {
            true => String::new(),
            // SAFETY: non-null: OIDN's NUL-terminated message, still valid (see above).
            false => unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned(),
        };
        Err(anyhow!("Open Image Denoise failed {what}: {text} (error {code})"))
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: the handle is live and owned here; filters and buffers made on it are released
        // before (they borrow the device).
        unsafe { (self.oidn.api.oidnReleaseDevice)(self.handle) };
    }
}

/// "2.5.1" for OIDN's 20501.
fn version_text(version: i32) -> String {
    format!("{}.{}.{}", version / 10000, version / 100 % 100, version % 100)
}

/// The first OIDN physical device, not the CPU, whose UUID (where it reports one) `accept`s: its
/// index, kind and name.
fn gpu_where(oidn: &Oidn, accept: impl Fn(Option<&[u8]>) -> bool) -> Option<(i32, DeviceKind, String)> {
    let api = &oidn.api;
    // SAFETY: a plain query; it loads OIDN's device modules (a CUDA one without a driver is skipped).
    let count = unsafe { (api.oidnGetNumPhysicalDevices)() };
    (0..count).find_map(|id| {
        // SAFETY: `id` is below the count OIDN reported; names are static NUL-terminated strings.
        let kind = DeviceKind::from_oidn(unsafe { (api.oidnGetPhysicalDeviceInt)(id, c"type".as_ptr()) })?;
        if kind == DeviceKind::Cpu {
            return None;
        }
        // SAFETY: as above.
        let has_uuid = unsafe { (api.oidnGetPhysicalDeviceBool)(id, c"uuidSupported".as_ptr()) };
        let mut size = 0usize;
        let data = match has_uuid {
            // SAFETY: as above; OIDN returns a pointer to `size` bytes it owns, read at once.
            true => unsafe { (api.oidnGetPhysicalDeviceData)(id, c"uuid".as_ptr(), &mut size) },
            false => std::ptr::null(),
        };
        let uuid = (!data.is_null() && size == ffi::UUID_SIZE)
            // SAFETY: `data` points to `size` (= UUID_SIZE) readable bytes.
            .then(|| unsafe { std::slice::from_raw_parts(data.cast::<u8>(), size) });
        accept(uuid).then(|| (id, kind, physical_name(oidn, id)))
    })
}

/// The name of OIDN's CPU physical device (the processor's model), or empty.
fn cpu_name(oidn: &Oidn) -> String {
    // SAFETY: plain queries as in `gpu_with_uuid`.
    let count = unsafe { (oidn.api.oidnGetNumPhysicalDevices)() };
    (0..count)
        // SAFETY: `id` is below the count.
        .find(|&id| unsafe { (oidn.api.oidnGetPhysicalDeviceInt)(id, c"type".as_ptr()) } == ffi::DEVICE_TYPE_CPU)
        .map(|id| physical_name(oidn, id))
        .unwrap_or_default()
}

fn physical_name(oidn: &Oidn, id: i32) -> String {
    // SAFETY: `id` is a reported physical device; the result is OIDN's NUL-terminated string or null.
    let name = unsafe { (oidn.api.oidnGetPhysicalDeviceString)(id, c"name".as_ptr()) };
    match name.is_null() {
        true => String::new(),
        // SAFETY: non-null and NUL-terminated, owned by OIDN; copied at once.
        false => unsafe { CStr::from_ptr(name) }.to_string_lossy().trim().to_owned(),
    }
}

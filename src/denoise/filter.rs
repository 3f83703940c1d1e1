//! Running OIDN's "RT" filter (ray-traced images) on host images: each image goes into an OIDN
//! buffer (device memory on a GPU device, host memory on the CPU) and the output comes back, so the
//! same code serves every device kind.

use super::device::Device;
use super::ffi::{self, BufferHandle, FilterHandle};
use anyhow::{bail, Result};
use std::ffi::{c_int, CString};

/// An OIDN buffer holding one RGB float image.
pub(super) struct Buffer<'d> {
    device: &'d Device,
    handle: BufferHandle,
    bytes: usize,
}

impl<'d> Buffer<'d> {
    /// A buffer holding `pixels`.
    pub fn with(device: &'d Device, pixels: &[[f32; 3]]) -> Result<Self> {
        let bytes = std::mem::size_of_val(pixels);
        // SAFETY: the device handle is live (borrowed); a size in bytes.
        let handle = unsafe { (device.oidn.api.oidnNewBuffer)(device.handle, bytes) };
        device.check("allocating a buffer")?;
        if handle.is_null() {
            bail!("Open Image Denoise could not allocate a buffer of {bytes} bytes");
        }
        let buffer = Self { device, handle, bytes };
        // SAFETY: the buffer holds `bytes` bytes and `pixels` is `bytes` readable bytes; the write
        // is synchronous.
        unsafe { (device.oidn.api.oidnWriteBuffer)(handle, 0, bytes, pixels.as_ptr().cast()) };
        device.check("writing a buffer")?;
        Ok(buffer)
    }

    /// The buffer's pixels.
    pub fn read(&self) -> Result<Vec<[f32; 3]>> {
        let mut pixels = vec![[0.0f32; 3]; self.bytes / 12];
        // SAFETY: `pixels` has room for the buffer's `bytes`; the read is synchronous.
        unsafe { (self.device.oidn.api.oidnReadBuffer)(self.handle, 0, self.bytes, pixels.as_mut_ptr().cast()) };
        self.device.check("reading a buffer")?;
        Ok(pixels)
    }
}

impl Drop for Buffer<'_> {
    fn drop(&mut self) {
        // SAFETY: owned, live handle; no filter that uses it runs after this (filters are dropped
        // first or have finished: execution is synchronous).
        unsafe { (self.device.oidn.api.oidnReleaseBuffer)(self.handle) };
    }
}

/// One "RT" filter, configured and run once.
pub(super) struct Filter<'d> {
    device: &'d Device,
    handle: FilterHandle,
    width: usize,
    height: usize,
}

impl<'d> Filter<'d> {
    pub fn new(device: &'d Device, width: u32, height: u32) -> Result<Self> {
        // SAFETY: live device; "RT" is a NUL-terminated static string.
        let handle = unsafe { (device.oidn.api.oidnNewFilter)(device.handle, c"RT".as_ptr()) };
        device.check("creating its RT filter")?;
        if handle.is_null() {
            bail!("Open Image Denoise could not create its RT filter");
        }
        Ok(Self { device, handle, width: width as usize, height: height as usize })
    }

    /// Binds `buffer` as the image `name` ("color", "albedo", "normal", "output"). The buffer must
    /// outlive the filter's execution, which `'d` and `run` taking `&self` see to.
    pub fn image(&self, name: &str, buffer: &Buffer<'d>) {
        let name = CString::new(name).expect("image names have no NUL");
        // SAFETY: live filter and buffer of one device; the buffer holds width x height packed
        // FLOAT3 pixels (strides 0: packed), as the caller made it from an image of that size.
        unsafe {
            (self.device.oidn.api.oidnSetFilterImage)(
                self.handle,
                name.as_ptr(),
                buffer.handle,
                ffi::FORMAT_FLOAT3,
                self.width,
                self.height,
                0,
                0,
                0,
            )
        };
    }

    pub fn set_bool(&self, name: &str, value: bool) {
        let name = CString::new(name).expect("parameter names have no NUL");
        // SAFETY: live filter; `name` is NUL-terminated and outlives the call.
        unsafe { (self.device.oidn.api.oidnSetFilterBool)(self.handle, name.as_ptr(), value) };
    }

    pub fn set_int(&self, name: &str, value: c_int) {
        let name = CString::new(name).expect("parameter names have no NUL");
        // SAFETY: as in `set_bool`.
        unsafe { (self.device.oidn.api.oidnSetFilterInt)(self.handle, name.as_ptr(), value) };
    }

    /// Commits and executes the filter (synchronously).
    pub fn run(&self, what: &str) -> Result<()> {
        // SAFETY: live filter whose images were bound to live buffers.
        unsafe { (self.device.oidn.api.oidnCommitFilter)(self.handle) };
        self.device.check(&format!("setting up {what}"))?;
        // SAFETY: as above; execution is synchronous, so the buffers are done with on return.
        unsafe { (self.device.oidn.api.oidnExecuteFilter)(self.handle) };
        self.device.check(&format!("running {what}"))
    }
}

impl Drop for Filter<'_> {
    fn drop(&mut self) {
        // SAFETY: owned, live handle.
        unsafe { (self.device.oidn.api.oidnReleaseFilter)(self.handle) };
    }
}

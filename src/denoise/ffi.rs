//! The part of Open Image Denoise 2's C API (`OpenImageDenoise/oidn.h`) that caustica calls, bound
//! at run time from a loaded `libOpenImageDenoise.so.2`: never linked at build time, so caustica
//! builds and runs where OIDN is not installed. Types and values are the header's, OIDN 2.5.

use libloading::Library;
use std::ffi::{c_char, c_int, c_void};

/// `OIDNDevice`, `OIDNFilter`, `OIDNBuffer`: opaque handles, null on failure.
pub type DeviceHandle = *mut c_void;
pub type FilterHandle = *mut c_void;
pub type BufferHandle = *mut c_void;

/// `OIDNDeviceType`.
pub const DEVICE_TYPE_CPU: c_int = 1;
pub const DEVICE_TYPE_SYCL: c_int = 2;
pub const DEVICE_TYPE_CUDA: c_int = 3;
pub const DEVICE_TYPE_HIP: c_int = 4;
pub const DEVICE_TYPE_METAL: c_int = 5;

/// `OIDNError`: `OIDN_ERROR_NONE`.
pub const ERROR_NONE: c_int = 0;

/// `OIDNFormat`: `OIDN_FORMAT_FLOAT3`.
pub const FORMAT_FLOAT3: c_int = 3;

/// `OIDNQuality`.
pub const QUALITY_FAST: c_int = 4;
pub const QUALITY_BALANCED: c_int = 5;
pub const QUALITY_HIGH: c_int = 6;

/// `OIDN_UUID_SIZE`.
pub const UUID_SIZE: usize = 16;

/// Declares [`Api`]: one function pointer per C function, looked up by its name.
macro_rules! oidn_api {
    ($($name:ident: fn($($arg:ty),*) $(-> $ret:ty)?;)*) => {
        /// The C functions, resolved from one library; valid while that library stays loaded
        /// (`Library` holds it with them).
        #[allow(non_snake_case)]
        pub struct Api {
            $(
                // SAFETY: a field's type only; each call site states why its arguments are valid.
                pub $name: unsafe extern "C" fn($($arg),*) $(-> $ret)?,
            )*
        }

        impl Api {
            /// Resolves every function in `library`; the name of the first it lacks otherwise.
            fn resolve(library: &Library) -> Result<Self, &'static str> {
                Ok(Self {
                    $(
                        // SAFETY: the symbol is OIDN's function of this name, whose C signature
                        // (oidn.h, 2.x) is the field's type; a library that is not OIDN 2 but
                        // exports the names is refused by its version before any other call
                        // (`Device::new`).
                        $name: *unsafe { library.get(concat!(stringify!($name), "\0").as_bytes()) }
                            .map_err(|_| stringify!($name))?,
                    )*
                })
            }
        }
    };
}

oidn_api! {
    oidnGetNumPhysicalDevices: fn() -> c_int;
    oidnGetPhysicalDeviceInt: fn(c_int, *const c_char) -> c_int;
    oidnGetPhysicalDeviceBool: fn(c_int, *const c_char) -> bool;
    oidnGetPhysicalDeviceString: fn(c_int, *const c_char) -> *const c_char;
    oidnGetPhysicalDeviceData: fn(c_int, *const c_char, *mut usize) -> *const c_void;
    oidnNewDevice: fn(c_int) -> DeviceHandle;
    oidnNewDeviceByID: fn(c_int) -> DeviceHandle;
    oidnCommitDevice: fn(DeviceHandle);
    oidnGetDeviceInt: fn(DeviceHandle, *const c_char) -> c_int;
    oidnGetDeviceError: fn(DeviceHandle, *mut *const c_char) -> c_int;
    oidnReleaseDevice: fn(DeviceHandle);
    oidnNewBuffer: fn(DeviceHandle, usize) -> BufferHandle;
    oidnWriteBuffer: fn(BufferHandle, usize, usize, *const c_void);
    oidnReadBuffer: fn(BufferHandle, usize, usize, *mut c_void);
    oidnReleaseBuffer: fn(BufferHandle);
    oidnNewFilter: fn(DeviceHandle, *const c_char) -> FilterHandle;
    oidnSetFilterImage: fn(FilterHandle, *const c_char, BufferHandle, c_int, usize, usize, usize, usize, usize);
    oidnSetFilterBool: fn(FilterHandle, *const c_char, bool);
    oidnSetFilterInt: fn(FilterHandle, *const c_char, c_int);
    oidnCommitFilter: fn(FilterHandle);
    oidnExecuteFilter: fn(FilterHandle);
    oidnReleaseFilter: fn(FilterHandle);
}

/// A loaded OIDN library and its functions.
pub struct Oidn {
    pub api: Api,
    // Dropped after `api`: the pointers are valid only while the library is loaded.
    _library: Library,
}

impl Oidn {
    /// Takes a loaded library; the name of the first function it lacks otherwise.
    pub fn from_library(library: Library) -> Result<Self, &'static str> {
        let api = Api::resolve(&library)?;
        Ok(Self { api, _library: library })
    }
}

//! libudev, loaded when first used.
//!
//! gilrs (through gilrs-core) calls libudev to find and watch gamepads. The crates.io
//! `libudev-sys` links `-ludev` at build time, found with pkg-config, which makes every build
//! need `pkg-config` and `libudev-dev` and every run need `libudev.so.1`. This crate keeps the
//! names and signatures gilrs-core 0.6 calls and resolves each function from `libudev.so.1`
//! with `dlopen`/`dlsym` the first time any of them is called (as SDL does). Where the
//! library cannot be loaded, every function fails the way libudev itself reports failure
//! (`NULL`, or a negative errno): `udev_new` returns `NULL`, gilrs reports it cannot create a
//! udev context, and the program goes on without gamepads. [`available`] tells a caller why
//! beforehand.
//!
//! Only the functions gilrs-core uses are here; a gilrs update calling another one fails to
//! build (not to run), which is when to add it.

// libudev is Linux's: elsewhere (the Windows and macOS cross checks build the workspace) the
// crate is empty, as nothing there calls it.
#![cfg(target_os = "linux")]
#![allow(non_camel_case_types)]
#![allow(clippy::missing_safety_doc)]

use libc::{c_char, c_int, c_void};
use std::ffi::CStr;
use std::sync::OnceLock;

/// The library's name: the ABI-versioned file every distribution ships (the unversioned
/// `libudev.so` comes only with the -dev package).
pub const LIBRARY: &CStr = c"libudev.so.1";

macro_rules! opaque {
    ($($name:ident),*) => {$(
        #[repr(C)]
        pub struct $name {
            __private: c_void,
        }
    )*};
}
opaque!(
    udev,
    udev_list_entry,
    udev_device,
    udev_monitor,
    udev_enumerate
);

/// Declares the functions: a table of pointers resolved together, and for each a wrapper
/// with libudev's signature that calls through the table or returns `$fail` without it.
macro_rules! functions {
    ($(fn $name:ident($($arg:ident: $ty:ty),*) -> $ret:ty = $fail:expr;)*) => {
        /// Every function, resolved from one loaded library.
        #[derive(Clone, Copy)]
        struct Table {
            $($name: unsafe extern "C" fn($($ty),*) -> $ret,)*
        }

        impl Table {
            /// Resolve every function from `handle`, or name the first one missing.
            unsafe fn resolve(handle: *mut c_void) -> Result<Table, String> {
                Ok(Table {
                    $($name: {
                        let name = concat!(stringify!($name), "\0");
                        // SAFETY: a NUL-terminated name; a non-null result is the address of
                        // libudev's function of that name, whose C signature is the one
                        // declared here (libudev.h, stable since libudev.so.1).
                        let f = unsafe { libc::dlsym(handle, name.as_ptr().cast()) };
                        if f.is_null() {
                            return Err(format!("{} has no {}", LIBRARY.to_string_lossy(), stringify!($name)));
                        }
                        unsafe { std::mem::transmute::<*mut c_void, unsafe extern "C" fn($($ty),*) -> $ret>(f) }
                    },)*
                })
            }
        }

        $(
            pub unsafe fn $name($($arg: $ty),*) -> $ret {
                match table() {
                    // SAFETY: the caller keeps libudev's contract for this function.
                    Ok(t) => unsafe { (t.$name)($($arg),*) },
                    Err(_) => $fail,
                }
            }
        )*
    };
}

const NO_LIBRARY: c_int = -libc::ENOSYS;

functions! {
    fn udev_new() -> *mut udev = std::ptr::null_mut();
    fn udev_ref(udev: *mut udev) -> *mut udev = std::ptr::null_mut();
    fn udev_unref(udev: *mut udev) -> *mut udev = std::ptr::null_mut();
    fn udev_list_entry_get_next(list_entry: *mut udev_list_entry) -> *mut udev_list_entry = std::ptr::null_mut();
    fn udev_list_entry_get_name(list_entry: *mut udev_list_entry) -> *const c_char = std::ptr::null();
    fn udev_list_entry_get_value(list_entry: *mut udev_list_entry) -> *const c_char = std::ptr::null();
    fn udev_device_ref(udev_device: *mut udev_device) -> *mut udev_device = std::ptr::null_mut();
    fn udev_device_unref(udev_device: *mut udev_device) -> *mut udev_device = std::ptr::null_mut();
    fn udev_device_new_from_syspath(udev: *mut udev, syspath: *const c_char) -> *mut udev_device = std::ptr::null_mut();
    fn udev_device_get_syspath(udev_device: *mut udev_device) -> *const c_char = std::ptr::null();
    fn udev_device_get_devnode(udev_device: *mut udev_device) -> *const c_char = std::ptr::null();
    fn udev_device_get_properties_list_entry(udev_device: *mut udev_device) -> *mut udev_list_entry = std::ptr::null_mut();
    fn udev_device_get_property_value(udev_device: *mut udev_device, key: *const c_char) -> *const c_char = std::ptr::null();
    fn udev_device_get_action(udev_device: *mut udev_device) -> *const c_char = std::ptr::null();
    fn udev_monitor_unref(udev_monitor: *mut udev_monitor) -> *mut udev_monitor = std::ptr::null_mut();
    fn udev_monitor_new_from_netlink(udev: *mut udev, name: *const c_char) -> *mut udev_monitor = std::ptr::null_mut();
    fn udev_monitor_enable_receiving(udev_monitor: *mut udev_monitor) -> c_int = NO_LIBRARY;
    fn udev_monitor_get_fd(udev_monitor: *mut udev_monitor) -> c_int = NO_LIBRARY;
    fn udev_monitor_receive_device(udev_monitor: *mut udev_monitor) -> *mut udev_device = std::ptr::null_mut();
    fn udev_monitor_filter_add_match_subsystem_devtype(udev_monitor: *mut udev_monitor, subsystem: *const c_char, devtype: *const c_char) -> c_int = NO_LIBRARY;
    fn udev_enumerate_unref(udev_enumerate: *mut udev_enumerate) -> *mut udev_enumerate = std::ptr::null_mut();
    fn udev_enumerate_new(udev: *mut udev) -> *mut udev_enumerate = std::ptr::null_mut();
    fn udev_enumerate_add_match_subsystem(udev_enumerate: *mut udev_enumerate, subsystem: *const c_char) -> c_int = NO_LIBRARY;
    fn udev_enumerate_add_match_property(udev_enumerate: *mut udev_enumerate, property: *const c_char, value: *const c_char) -> c_int = NO_LIBRARY;
    fn udev_enumerate_scan_devices(udev_enumerate: *mut udev_enumerate) -> c_int = NO_LIBRARY;
    fn udev_enumerate_get_list_entry(udev_enumerate: *mut udev_enumerate) -> *mut udev_list_entry = std::ptr::null_mut();
}

/// Open `library` and resolve every function from it. The handle is never closed: the
/// functions stay valid for the life of the process.
fn open(library: &CStr) -> Result<Table, String> {
    // SAFETY: a NUL-terminated name; libudev's initialisers have no requirements.
    let handle = unsafe { libc::dlopen(library.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
    if handle.is_null() {
        // SAFETY: dlerror's message (if any) is valid until the next dl* call on this thread.
        let why = unsafe {
            let e = libc::dlerror();
            if e.is_null() {
                "not found".to_string()
            } else {
                CStr::from_ptr(e).to_string_lossy().into_owned()
            }
        };
        return Err(why);
    }
    // SAFETY: a live handle, never closed.
    unsafe { Table::resolve(handle) }
}

/// The library name to load: [`LIBRARY`], unless `DROIDCTL_LIBUDEV` names another file (the
/// tests use it to try a machine without libudev).
fn library_name() -> std::ffi::CString {
    std::env::var_os("DROIDCTL_LIBUDEV")
        .and_then(|v| {
            use std::os::unix::ffi::OsStringExt;
            std::ffi::CString::new(v.into_vec()).ok()
        })
        .unwrap_or_else(|| LIBRARY.to_owned())
}

fn table() -> &'static Result<Table, String> {
    static TABLE: OnceLock<Result<Table, String>> = OnceLock::new();
    TABLE.get_or_init(|| open(&library_name()))
}

/// Whether libudev could be loaded (loading it now if nobody has yet), and why not.
pub fn available() -> Result<(), String> {
    table().as_ref().map(|_| ()).map_err(Clone::clone)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_library_is_an_error_not_a_crash() {
        let e = open(c"libudev-that-is-not-there.so.1")
            .err()
            .expect("no such library");
        assert!(e.contains("libudev-that-is-not-there"), "{e}");
    }

    #[test]
    fn every_function_resolves_from_the_real_library() {
        // Debian, Fedora, Arch and Alpine all ship libudev.so.1 in their base system (systemd's
        // or eudev's); a machine without it has no udev to find gamepads with anyway.
        match open(LIBRARY) {
            Ok(t) => {
                let u = unsafe { (t.udev_new)() };
                assert!(!u.is_null(), "udev_new through dlsym");
                unsafe { (t.udev_unref)(u) };
            }
            Err(e) if e.contains("No such file") || e.contains("cannot open") => {
                eprintln!("no libudev.so.1 on this machine: {e}")
            }
            Err(e) => panic!("{e}"),
        }
    }
}

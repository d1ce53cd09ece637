//! A plugin library written against the C ABI by hand, without the sdk — as a C author would —
//! compiled by `tests/plugin_host.rs` with `rustc` directly, once per variant:
//! `--cfg 'variant="bad_magic"'`, `"wrong_major"`, `"short_struct"`, or none (a well-formed
//! header); built with `-C panic=abort`, its header says so (`panic_unwind` = 0).
//! The layout below is ABI v1's (`sdk/src/abi/v1.rs`, snapshot in
//! `sdk/tests/snapshots/abi_layout__abi_v1_layout.snap`).

#![allow(dead_code)]

use std::ffi::c_void;

#[repr(C)]
struct AbiStr {
    ptr: *const u8,
    len: usize,
}

const fn s(text: &'static str) -> AbiStr {
    AbiStr {
        ptr: text.as_ptr(),
        len: text.len(),
    }
}

#[repr(C)]
struct Header {
    magic: [u8; 8],
    abi_major: u32,
    abi_minor: u32,
    struct_size: u32,
    panic_unwind: u8,
    reserved: [u8; 3],
    sdk_version: AbiStr,
    rustc_version: AbiStr,
    name: AbiStr,
    version: AbiStr,
    description: AbiStr,
    kind: u32,
    param_count: u32,
    params: *const c_void,
    create: Option<unsafe extern "C" fn(*mut *mut c_void, *mut c_void) -> u32>,
    destroy: Option<unsafe extern "C" fn(*mut c_void)>,
    prepare: Option<unsafe extern "C" fn(*mut c_void, *const c_void, *mut c_void) -> u32>,
    render: Option<
        unsafe extern "C" fn(*mut c_void, *const c_void, *const f64, u32, *mut c_void, *mut c_void) -> u32,
    >,
}

struct Shared(Header);
// SAFETY: immutable, and every pointer points at static data.
unsafe impl Sync for Shared {}

const MAGIC: [u8; 8] = if cfg!(variant = "bad_magic") {
    *b"NOTAFLAR"
} else {
    *b"FLAREPLG"
};
const MAJOR: u32 = if cfg!(variant = "wrong_major") { 2 } else { 1 };
const SIZE: u32 = if cfg!(variant = "short_struct") {
    // A header cut off after the description: the fields an older draft had.
    104
} else {
    std::mem::size_of::<Header>() as u32
};

unsafe extern "C" fn create(instance: *mut *mut c_void, _error: *mut c_void) -> u32 {
    // SAFETY: the host passes a valid pointer; a non-null dummy instance.
    unsafe { *instance = std::ptr::NonNull::<u8>::dangling().as_ptr().cast() };
    0
}
unsafe extern "C" fn destroy(_instance: *mut c_void) {}
unsafe extern "C" fn prepare(_i: *mut c_void, _l: *const c_void, _e: *mut c_void) -> u32 {
    0
}
unsafe extern "C" fn render(
    _i: *mut c_void,
    _s: *const c_void,
    _p: *const f64,
    _n: u32,
    _o: *mut c_void,
    _e: *mut c_void,
) -> u32 {
    0
}

static HEADER: Shared = Shared(Header {
    magic: MAGIC,
    abi_major: MAJOR,
    abi_minor: 0,
    struct_size: SIZE,
    panic_unwind: cfg!(panic = "unwind") as u8,
    reserved: [0; 3],
    sdk_version: s("hand-written"),
    rustc_version: s("unknown"),
    name: s("misfit"),
    version: s("0.0.0"),
    description: s("a hand-written header for the host's tests"),
    kind: 2,
    param_count: 0,
    params: std::ptr::null(),
    create: Some(create),
    destroy: Some(destroy),
    prepare: Some(prepare),
    render: Some(render),
});

#[unsafe(no_mangle)]
pub extern "C" fn flarebench_plugin_v1() -> *const c_void {
    (&HEADER.0 as *const Header).cast()
}

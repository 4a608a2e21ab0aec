//! `libsightline`: the C ABI of [`sightline_runtime`], for engines (C, C++, C# through
//! P/Invoke, GDExtension). Every entry point returns a status code and never unwinds
//! into C: null pointers, bad paths, truncated or corrupted files and panics all come
//! back as negative codes with [`sightline_last_error_message`] saying why.
//!
//! Conventions: a handle comes from [`sightline_open`] or [`sightline_open_bytes`] and
//! goes back to [`sightline_close`]; it may be shared between threads (queries on one
//! handle are serialized). A list is returned by *count then fill*: the call always
//! writes the list's length to `*len_out`, copies the ids into `buf` when `cap` is large
//! enough (`SIGHTLINE_OK`), and returns `SIGHTLINE_BUFFER_TOO_SMALL` otherwise (call
//! again with a buffer of `*len_out` ids; `buf` may be NULL when `cap` is 0).
//! Gameplay queries carry the guarantee of `sightline_runtime::gameplay`.

use sightline_runtime::{Pvs, Query, RuntimeError};
use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Mutex, MutexGuard};

/// The version of this ABI: bumped whenever a function's signature or meaning changes.
pub const SIGHTLINE_ABI_VERSION: u32 = 1;

/// Success.
pub const SIGHTLINE_OK: i32 = 0;
/// No cell holds the point, or the file has no such data (no source map).
pub const SIGHTLINE_NOT_FOUND: i32 = 1;
/// The caller's buffer is too small: `*len_out` says how many ids are needed.
pub const SIGHTLINE_BUFFER_TOO_SMALL: i32 = 2;
/// A required pointer was NULL.
pub const SIGHTLINE_ERR_NULL_POINTER: i32 = -1;
/// A bad argument: a path that is not UTF-8, a cell the file does not have or store.
pub const SIGHTLINE_ERR_INVALID_ARGUMENT: i32 = -2;
/// The file could not be read.
pub const SIGHTLINE_ERR_IO: i32 = -3;
/// Not a `.pvs` file (bad magic number).
pub const SIGHTLINE_ERR_NOT_PVS: i32 = -4;
/// A `.pvs` format version this library does not read.
pub const SIGHTLINE_ERR_VERSION: i32 = -5;
/// The file is shorter than its tables say.
pub const SIGHTLINE_ERR_TRUNCATED: i32 = -6;
/// A checksum mismatch or an inconsistent table.
pub const SIGHTLINE_ERR_CORRUPT: i32 = -7;
/// A bug in libsightline (a caught panic); the handle remains usable.
pub const SIGHTLINE_ERR_PANIC: i32 = -99;

/// An open `.pvs` (opaque).
pub struct SightlinePvs {
    pvs: Pvs,
    scratch: Mutex<Scratch>,
}

struct Scratch {
    query: Query,
    list: Vec<u32>,
    other: Vec<u32>,
}

struct Fail {
    code: i32,
    message: String,
}

fn fail(code: i32, message: impl Into<String>) -> Fail {
    Fail {
        code,
        message: message.into(),
    }
}

impl From<RuntimeError> for Fail {
    fn from(e: RuntimeError) -> Fail {
        let code = match &e {
            RuntimeError::Io { .. } => SIGHTLINE_ERR_IO,
            RuntimeError::NotPvs => SIGHTLINE_ERR_NOT_PVS,
            RuntimeError::Version { .. } => SIGHTLINE_ERR_VERSION,
            RuntimeError::Truncated(_) => SIGHTLINE_ERR_TRUNCATED,
            RuntimeError::Corrupt(_) => SIGHTLINE_ERR_CORRUPT,
            RuntimeError::Invalid(_) => SIGHTLINE_ERR_INVALID_ARGUMENT,
        };
        fail(code, e.to_string())
    }
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: &str) {
    let c = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

/// Run `f`, turning its failure or panic into a status code and the thread's message.
fn guard(f: impl FnOnce() -> Result<i32, Fail>) -> i32 {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(code)) => {
            if code == SIGHTLINE_OK {
                set_last_error("");
            }
            code
        }
        Ok(Err(e)) => {
            set_last_error(&e.message);
            e.code
        }
        Err(_) => {
            set_last_error("internal error in libsightline (a panic was caught)");
            SIGHTLINE_ERR_PANIC
        }
    }
}

fn handle<'a>(pvs: *const SightlinePvs) -> Result<&'a SightlinePvs, Fail> {
    // SAFETY: a non-null handle is one `sightline_open*` returned and `sightline_close`
    // has not freed (the documented contract).
    unsafe { pvs.as_ref() }.ok_or_else(|| fail(SIGHTLINE_ERR_NULL_POINTER, "the handle is NULL"))
}

fn scratch(h: &SightlinePvs) -> MutexGuard<'_, Scratch> {
    h.scratch.lock().unwrap_or_else(|p| p.into_inner())
}

fn write<T>(out: *mut T, value: T, what: &str) -> Result<(), Fail> {
    if out.is_null() {
        return Err(fail(SIGHTLINE_ERR_NULL_POINTER, format!("{what} is NULL")));
    }
    // SAFETY: non-null, and the caller passes a pointer to writable memory for a `T`.
    unsafe { out.write(value) };
    Ok(())
}

/// Count then fill (crate documentation).
fn fill(ids: &[u32], buf: *mut u32, cap: usize, len_out: *mut usize) -> Result<i32, Fail> {
    write(len_out, ids.len(), "len_out")?;
    if ids.len() > cap {
        return Ok(SIGHTLINE_BUFFER_TOO_SMALL);
    }
    if !ids.is_empty() {
        if buf.is_null() {
            return Err(fail(SIGHTLINE_ERR_NULL_POINTER, "buf is NULL"));
        }
        // SAFETY: `buf` holds `cap >= ids.len()` writable ids (the caller's contract),
        // and cannot overlap our own vector.
        unsafe { std::ptr::copy_nonoverlapping(ids.as_ptr(), buf, ids.len()) };
    }
    Ok(SIGHTLINE_OK)
}

fn open_with(out: *mut *mut SightlinePvs, open: impl FnOnce() -> Result<Pvs, Fail>) -> i32 {
    guard(|| {
        if out.is_null() {
            return Err(fail(SIGHTLINE_ERR_NULL_POINTER, "out is NULL"));
        }
        write(out, std::ptr::null_mut(), "out")?;
        let pvs = open()?;
        let h = Box::new(SightlinePvs {
            pvs,
            scratch: Mutex::new(Scratch {
                query: Query::new(),
                list: Vec::new(),
                other: Vec::new(),
            }),
        });
        write(out, Box::into_raw(h), "out")?;
        Ok(SIGHTLINE_OK)
    })
}

/// The library's version, e.g. `"0.1.0"` (a static string).
#[no_mangle]
pub extern "C" fn sightline_version() -> *const c_char {
    static VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "\0");
    VERSION.as_ptr().cast()
}

/// [`SIGHTLINE_ABI_VERSION`] of the library actually loaded (compare with the header's).
#[no_mangle]
pub extern "C" fn sightline_abi_version() -> u32 {
    SIGHTLINE_ABI_VERSION
}

/// The message of the last failed call on this thread (`""` after a success); valid
/// until the next call on this thread.
#[no_mangle]
pub extern "C" fn sightline_last_error_message() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// Open the `.pvs` at `path` (UTF-8, NUL-terminated) into `*out`.
///
/// # Safety
/// `path` is NULL or a NUL-terminated string; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn sightline_open(path: *const c_char, out: *mut *mut SightlinePvs) -> i32 {
    open_with(out, || {
        if path.is_null() {
            return Err(fail(SIGHTLINE_ERR_NULL_POINTER, "path is NULL"));
        }
        // SAFETY: non-null and NUL-terminated (the caller's contract).
        let path = unsafe { CStr::from_ptr(path) };
        let path = path
            .to_str()
            .map_err(|_| fail(SIGHTLINE_ERR_INVALID_ARGUMENT, "the path is not UTF-8"))?;
        Ok(Pvs::open(path)?)
    })
}

/// Open a `.pvs` held in memory (`len` bytes at `data`, copied) into `*out`.
///
/// # Safety
/// `data` is NULL or points to `len` readable bytes; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn sightline_open_bytes(
    data: *const u8,
    len: usize,
    out: *mut *mut SightlinePvs,
) -> i32 {
    open_with(out, || {
        if data.is_null() {
            return Err(fail(SIGHTLINE_ERR_NULL_POINTER, "data is NULL"));
        }
        // SAFETY: `len` readable bytes at `data` (the caller's contract).
        let bytes = unsafe { std::slice::from_raw_parts(data, len) };
        Ok(Pvs::from_bytes(bytes)?)
    })
}

/// Free a handle (NULL is ignored).
///
/// # Safety
/// `pvs` is NULL or a handle not yet closed; it must not be used afterwards.
#[no_mangle]
pub unsafe extern "C" fn sightline_close(pvs: *mut SightlinePvs) {
    if !pvs.is_null() {
        // SAFETY: a handle from `Box::into_raw` in `open_with`, closed once.
        let h = unsafe { Box::from_raw(pvs) };
        let _ = catch_unwind(AssertUnwindSafe(move || drop(h)));
    }
}

/// The number of cells (`*out`).
#[no_mangle]
pub extern "C" fn sightline_cell_count(pvs: *const SightlinePvs, out: *mut u32) -> i32 {
    guard(|| {
        write(out, handle(pvs)?.pvs.cell_count(), "out")?;
        Ok(SIGHTLINE_OK)
    })
}

/// The number of objects of the scene (`*out`): every visible id is below it.
#[no_mangle]
pub extern "C" fn sightline_object_count(pvs: *const SightlinePvs, out: *mut u32) -> i32 {
    guard(|| {
        write(out, handle(pvs)?.pvs.object_count(), "out")?;
        Ok(SIGHTLINE_OK)
    })
}

/// The box of cell `cell` as `x0, y0, z0, x1, y1, z1` into `out[6]`.
#[no_mangle]
pub extern "C" fn sightline_cell_box(pvs: *const SightlinePvs, cell: u32, out: *mut f64) -> i32 {
    guard(|| {
        let b = handle(pvs)?
            .pvs
            .cell_box(cell)
            .ok_or_else(|| fail(SIGHTLINE_ERR_INVALID_ARGUMENT, format!("no cell {cell}")))?;
        write(out.cast::<[f64; 6]>(), b, "out")?;
        Ok(SIGHTLINE_OK)
    })
}

/// The cell holding the point `(x, y, z)` into `*cell_out` (the lowest index on shared
/// faces); `SIGHTLINE_NOT_FOUND` when no cell does.
#[no_mangle]
pub extern "C" fn sightline_locate(
    pvs: *const SightlinePvs,
    x: f64,
    y: f64,
    z: f64,
    cell_out: *mut u32,
) -> i32 {
    guard(|| {
        let h = handle(pvs)?;
        match h.pvs.locate([x, y, z]) {
            Some(c) => {
                write(cell_out, c, "cell_out")?;
                Ok(SIGHTLINE_OK)
            }
            None => {
                set_last_error(&format!("no cell holds the point {x},{y},{z}"));
                Ok(SIGHTLINE_NOT_FOUND)
            }
        }
    })
}

/// The sorted visible ids of cell `cell` (count then fill).
#[no_mangle]
pub extern "C" fn sightline_visible(
    pvs: *const SightlinePvs,
    cell: u32,
    buf: *mut u32,
    cap: usize,
    len_out: *mut usize,
) -> i32 {
    guard(|| {
        let h = handle(pvs)?;
        let mut s = scratch(h);
        let s = &mut *s;
        h.pvs.visible_into(&mut s.query, cell, &mut s.list)?;
        fill(&s.list, buf, cap, len_out)
    })
}

/// The sorted visible leaves of cell `cell` (count then fill); `SIGHTLINE_NOT_FOUND`
/// when the file stores none (only BSP levels' builds do).
#[no_mangle]
pub extern "C" fn sightline_visible_leaves(
    pvs: *const SightlinePvs,
    cell: u32,
    buf: *mut u32,
    cap: usize,
    len_out: *mut usize,
) -> i32 {
    guard(|| {
        let h = handle(pvs)?;
        match h.pvs.visible_leaves(cell) {
            Some(l) => fill(l, buf, cap, len_out),
            None => {
                write(len_out, 0, "len_out")?;
                set_last_error("the file stores no visible leaves for this cell");
                Ok(SIGHTLINE_NOT_FOUND)
            }
        }
    })
}

/// The sorted source objects of cell `cell`'s visible ids (a mesh level's map; count
/// then fill); `SIGHTLINE_NOT_FOUND` when the file has no map.
#[no_mangle]
pub extern "C" fn sightline_visible_sources(
    pvs: *const SightlinePvs,
    cell: u32,
    buf: *mut u32,
    cap: usize,
    len_out: *mut usize,
) -> i32 {
    guard(|| {
        let h = handle(pvs)?;
        let mut s = scratch(h);
        let s = &mut *s;
        h.pvs.visible_into(&mut s.query, cell, &mut s.other)?;
        if !h.pvs.visible_sources_into(&s.other, &mut s.list) {
            write(len_out, 0, "len_out")?;
            set_last_error("the file has no source map");
            return Ok(SIGHTLINE_NOT_FOUND);
        }
        fill(&s.list, buf, cap, len_out)
    })
}

/// The cells whose boxes touch cell `cell`'s, to prefetch (count then fill).
#[no_mangle]
pub extern "C" fn sightline_neighbours(
    pvs: *const SightlinePvs,
    cell: u32,
    buf: *mut u32,
    cap: usize,
    len_out: *mut usize,
) -> i32 {
    guard(|| {
        let h = handle(pvs)?;
        if cell >= h.pvs.cell_count() {
            return Err(fail(
                SIGHTLINE_ERR_INVALID_ARGUMENT,
                format!("no cell {cell}"),
            ));
        }
        let mut s = scratch(h);
        h.pvs.neighbours_into(cell, &mut s.list);
        fill(&s.list, buf, cap, len_out)
    })
}

/// Whether cell `a` may see cell `b` into `*out` (1 or 0; never 0 when a sight line
/// exists, within the guarantee of `sightline_runtime::gameplay`).
#[no_mangle]
pub extern "C" fn sightline_can_see(
    pvs: *const SightlinePvs,
    a: u32,
    b: u32,
    out: *mut i32,
) -> i32 {
    guard(|| {
        let h = handle(pvs)?;
        let seen = h.pvs.can_see(&mut scratch(h).query, a, b)?;
        write(out, seen as i32, "out")?;
        Ok(SIGHTLINE_OK)
    })
}

/// The cells that may see cell `cell`, ascending (count then fill).
#[no_mangle]
pub extern "C" fn sightline_cells_seeing(
    pvs: *const SightlinePvs,
    cell: u32,
    buf: *mut u32,
    cap: usize,
    len_out: *mut usize,
) -> i32 {
    guard(|| {
        let h = handle(pvs)?;
        let mut s = scratch(h);
        let s = &mut *s;
        h.pvs.cells_seeing_into(&mut s.query, cell, &mut s.list)?;
        fill(&s.list, buf, cap, len_out)
    })
}

/// The cells that may see the point `(x, y, z)`, ascending (count then fill);
/// `SIGHTLINE_NOT_FOUND` when no cell holds the point.
#[no_mangle]
pub extern "C" fn sightline_cells_seeing_point(
    pvs: *const SightlinePvs,
    x: f64,
    y: f64,
    z: f64,
    buf: *mut u32,
    cap: usize,
    len_out: *mut usize,
) -> i32 {
    guard(|| {
        let h = handle(pvs)?;
        let mut s = scratch(h);
        let s = &mut *s;
        match h
            .pvs
            .cells_seeing_point_into(&mut s.query, [x, y, z], &mut s.list)?
        {
            Some(_) => fill(&s.list, buf, cap, len_out),
            None => {
                write(len_out, 0, "len_out")?;
                set_last_error(&format!("no cell holds the point {x},{y},{z}"));
                Ok(SIGHTLINE_NOT_FOUND)
            }
        }
    })
}

/// The secondary PVS of cell `cell`: the union of the rows of the cells that may see
/// it, ascending (count then fill).
#[no_mangle]
pub extern "C" fn sightline_secondary(
    pvs: *const SightlinePvs,
    cell: u32,
    buf: *mut u32,
    cap: usize,
    len_out: *mut usize,
) -> i32 {
    guard(|| {
        let h = handle(pvs)?;
        let mut s = scratch(h);
        let s = &mut *s;
        h.pvs.secondary_into(&mut s.query, cell, &mut s.list)?;
        fill(&s.list, buf, cap, len_out)
    })
}

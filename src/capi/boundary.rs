//! The boundary every C function crosses: the live-handle registries, the thread-local last
//! error, the catch of panics, and the checks of pointers, lengths and handles.

use std::cell::RefCell;
use std::collections::HashSet;
use std::panic::{catch_unwind, AssertUnwindSafe};

use super::*;

thread_local! {
    pub(super) static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

pub(super) type Registry = Mutex<Option<HashSet<usize>>>;

/// Live world handles.
pub(super) static WORLDS: Registry = Mutex::new(None);
/// Live snapshot handles.
pub(super) static SNAPSHOTS: Registry = Mutex::new(None);

pub(super) fn live<R>(reg: &Registry, f: impl FnOnce(&mut HashSet<usize>) -> R) -> R {
    let mut g = reg.lock().unwrap_or_else(|p| p.into_inner());
    f(g.get_or_insert_with(HashSet::new))
}

pub(super) fn set_error(msg: &str) {
    let c = CString::new(msg.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

pub(super) type Fail = (WeftStatus, String);

pub(super) fn fail(s: WeftStatus, msg: impl Into<String>) -> Fail {
    (s, msg.into())
}

impl From<WeftError> for Fail {
    fn from(e: WeftError) -> Fail {
        (WeftStatus::of(&e), e.to_string())
    }
}

/// Runs `f` with the panic net and the error bookkeeping of every entry point.
pub(super) fn boundary(f: impl FnOnce() -> Result<(), Fail>) -> WeftStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => {
            set_error("");
            WeftStatus::Ok
        }
        Ok(Err((s, msg))) => {
            set_error(&msg);
            s
        }
        Err(p) => {
            let what = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            set_error(&format!("internal panic in weft: {what}"));
            WeftStatus::Panic
        }
    }
}

pub(super) fn bad_handle(what: &str) -> Fail {
    fail(
        WeftStatus::InvalidHandle,
        format!("invalid {what} handle (null, unknown or destroyed)"),
    )
}

pub(super) fn world_mut<'a>(h: *mut WeftWorld) -> Result<&'a mut World, Fail> {
    if h.is_null() || !live(&WORLDS, |s| s.contains(&(h as usize))) {
        return Err(bad_handle("world"));
    }
    // SAFETY: the address is in the registry, so it came from `Box::into_raw` in
    // `register_world` and has not been freed; callers must not share one handle across
    // threads concurrently (documented).
    Ok(unsafe { &mut (*h).world })
}

pub(super) fn snapshot_ref<'a>(h: *const WeftSnapshot) -> Result<&'a Snapshot, Fail> {
    if h.is_null() || !live(&SNAPSHOTS, |s| s.contains(&(h as usize))) {
        return Err(bad_handle("snapshot"));
    }
    // SAFETY: in the registry, so from `Box::into_raw` in `weft_world_snapshot` and not freed;
    // only read here.
    Ok(unsafe { &(*h).snapshot })
}

pub(super) fn non_null<T>(p: *const T, name: &str) -> Result<(), Fail> {
    if p.is_null() {
        Err(fail(WeftStatus::NullPointer, format!("`{name}` is null")))
    } else {
        Ok(())
    }
}

/// Checks that `len` elements of `T` can be a slice (`from_raw_parts` needs the byte size to
/// fit `isize`).
pub(super) fn slice_len<T>(len: usize, name: &str) -> Result<(), Fail> {
    if len.checked_mul(std::mem::size_of::<T>()).is_some_and(|b| b <= isize::MAX as usize) {
        Ok(())
    } else {
        Err(fail(WeftStatus::InvalidArgument, format!("`{name}` length {len} is too large")))
    }
}

/// Borrows `len` readable elements at `p` (checked non-null and of a valid size).
///
/// # Safety
/// If non-null, `p` must point at `len` readable, initialised, aligned elements that stay
/// unchanged during the call.
pub(super) unsafe fn input<'a, T>(p: *const T, len: usize, name: &str) -> Result<&'a [T], Fail> {
    non_null(p, name)?;
    slice_len::<T>(len, name)?;
    // SAFETY: non-null, size checked; readable by the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// Borrows `len` writable elements at `p` (checked non-null and of a valid size).
///
/// # Safety
/// If non-null, `p` must point at `len` writable, aligned elements not otherwise in use during
/// the call.
pub(super) unsafe fn output<'a, T>(p: *mut T, len: usize, name: &str) -> Result<&'a mut [T], Fail> {
    non_null(p, name)?;
    slice_len::<T>(len, name)?;
    // SAFETY: non-null, size checked; writable and unaliased by the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// Reads three floats at `p`.
///
/// # Safety
/// If non-null, `p` must point at 3 readable floats.
pub(super) unsafe fn vec3(p: *const f32, name: &str) -> Result<[f32; 3], Fail> {
    // SAFETY: forwarded contract.
    let s = unsafe { input(p, 3, name) }?;
    Ok([s[0], s[1], s[2]])
}

/// Writes `v` to `*p` if `p` is non-null.
///
/// # Safety
/// If non-null, `p` must point at a writable `T`.
pub(super) unsafe fn put_opt<T>(p: *mut T, v: T) {
    if !p.is_null() {
        // SAFETY: non-null and writable by the caller's contract.
        unsafe { p.write(v) };
    }
}

/// Writes `v` to `*p`, which must not be null.
///
/// # Safety
/// If non-null, `p` must point at a writable `T`.
pub(super) unsafe fn put<T>(p: *mut T, v: T, name: &str) -> Result<(), Fail> {
    non_null(p, name)?;
    // SAFETY: non-null and writable by the caller's contract.
    unsafe { p.write(v) };
    Ok(())
}

/// Boxes a world, registers the handle and writes it to `out` (checked non-null by the caller).
///
/// # Safety
/// `out` must be non-null and writable.
pub(super) unsafe fn register_world(world: World, out: *mut *mut WeftWorld) {
    let h = Box::into_raw(Box::new(WeftWorld { world }));
    live(&WORLDS, |s| s.insert(h as usize));
    // SAFETY: non-null (checked by every caller) and writable by the contract.
    unsafe { out.write(h) };
}

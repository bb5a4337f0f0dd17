//! Initialising a value where it lives (a `static`, a `Box`), field by field, so that no
//! large value is built on the stack and moved: the twin is 60-120 KB, more than a
//! microcontroller's stack (Rust has no placement `new`; the optimiser may or may not
//! elide a by-value move, and at opt-level `s` it does not for values this large).
//!
//! The pattern (the nomicon's "initialising a struct field by field"): raw pointers to
//! the fields of a `MaybeUninit<S>`, each written once, then `assume_init_mut`.

use core::mem::MaybeUninit;

/// The uninitialised field behind `field` (from `addr_of_mut!((*p).field)` of a
/// `MaybeUninit`'s pointer), to initialise in place with the field type's own
/// in-place constructor.
///
/// # Safety
/// `field` must point to a field of a live, writable, possibly uninitialised value, and
/// nothing else may refer to that field while the returned reference lives.
pub(crate) unsafe fn uninit<'a, F>(field: *mut F) -> &'a mut MaybeUninit<F> {
    // SAFETY: `MaybeUninit<F>` has `F`'s layout; the caller vouches for the pointer.
    unsafe { &mut *field.cast::<MaybeUninit<F>>() }
}

/// The elements of an uninitialised array, each to initialise in place.
pub(crate) fn elements<E, const N: usize>(
    place: &mut MaybeUninit<[E; N]>,
) -> &mut [MaybeUninit<E>; N] {
    // SAFETY: `[MaybeUninit<E>; N]` has the layout of `[E; N]` and of `MaybeUninit<[E;
    // N]>`, and every bit pattern (initialised or not) is a valid value of it.
    unsafe { &mut *(place as *mut MaybeUninit<[E; N]>).cast::<[MaybeUninit<E>; N]>() }
}

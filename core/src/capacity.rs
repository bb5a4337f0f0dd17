//! Capacities per use: the storage of a [`Model`](crate::model::Model) and a
//! [`Workspace`](crate::workspace::Workspace) chosen by a type, so that one user (the
//! converter's twin, [`ccc::Twin`](crate::ccc::Twin)) holds models sized for its own
//! mechanisms while every other keeps the generic limits of [`config`](crate::config).
//!
//! A [`Capacity`] names, for each list of a model and each per-group array of a
//! workspace, a fixed-size storage ([`heapless::Vec`] and [`Array`]). Algorithms are
//! generic over it and read the storage as slices only, so a capacity changes how much
//! RAM a model takes, never a bit of what is computed: the loops run over the model's
//! own counts. [`Generic`], the default, is `config`'s limits.

use crate::config::{MAX_GROUND_POINTS, MAX_GROUPS, MAX_GROUP_JOINTS, MAX_LINKS, MAX_LOADS};
use crate::model::{Link, Load};
use crate::scalar::{Real, Vec2};
use crate::structomat::{Group, GroupData};
use crate::workspace::Reaction;
use core::fmt::Debug;
use core::mem::MaybeUninit;
use core::ops::{Deref, DerefMut};

/// The storage of a model's lists and of a workspace's per-group arrays, for scalar `T`.
/// Implemented by marker types: [`Generic`] (the default, `config`'s limits) and the
/// converter's own (`ccc::twin`).
pub trait Capacity<T: Real>: 'static {
    /// The ground points (world, m).
    type GroundPoints: List<Vec2<T>>;
    /// The moving links.
    type Links: List<Link<T>>;
    /// The motion-transmission sequence.
    type Groups: List<Group<T>>;
    /// The constant external loads.
    type Loads: List<Load<T>>;
    /// Each group's data in a workspace.
    type GroupData: ArrayStorage<GroupData<T>>;
    /// Each group's joint reactions in a workspace.
    type Reactions: ArrayStorage<[Reaction<T>; MAX_GROUP_JOINTS]>;
}

/// The generic core's capacities: `config`'s `MAX_*` limits (12 links, 12 ground
/// points, 8 groups, 8 loads).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Generic;

impl<T: Real> Capacity<T> for Generic {
    type GroundPoints = heapless::Vec<Vec2<T>, MAX_GROUND_POINTS>;
    type Links = heapless::Vec<Link<T>, MAX_LINKS>;
    type Groups = heapless::Vec<Group<T>, MAX_GROUPS>;
    type Loads = heapless::Vec<Load<T>, MAX_LOADS>;
    type GroupData = Array<GroupData<T>, MAX_GROUPS>;
    type Reactions = Array<[Reaction<T>; MAX_GROUP_JOINTS], MAX_GROUPS>;
}

/// A bounded list read as a slice: [`heapless::Vec`] of any capacity and length type.
pub trait List<E>: Deref<Target = [E]> + DerefMut + Clone + Debug {
    /// The largest number of elements.
    const CAPACITY: usize;
    /// An empty list.
    fn new() -> Self;
    /// Appends `e`, or hands it back when the list is full.
    fn push(&mut self, e: E) -> Result<(), E>;
    /// Removes and returns the last element.
    fn pop(&mut self) -> Option<E>;
    /// Removes every element.
    fn clear(&mut self);
    /// Whether the list holds [`List::CAPACITY`] elements.
    fn is_full(&self) -> bool {
        self.len() >= Self::CAPACITY
    }
}

impl<E: Clone + Debug, const N: usize, L: heapless::LenType> List<E> for heapless::Vec<E, N, L> {
    const CAPACITY: usize = N;
    fn new() -> Self {
        heapless::Vec::new()
    }
    fn push(&mut self, e: E) -> Result<(), E> {
        heapless::Vec::push(self, e)
    }
    fn pop(&mut self) -> Option<E> {
        heapless::Vec::pop(self)
    }
    fn clear(&mut self) {
        heapless::Vec::clear(self)
    }
}

/// `N` values of `E` read as a slice (a workspace's per-group arrays).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct Array<E, const N: usize>(pub [E; N]);

impl<E, const N: usize> Deref for Array<E, N> {
    type Target = [E];
    fn deref(&self) -> &[E] {
        &self.0
    }
}

impl<E, const N: usize> DerefMut for Array<E, N> {
    fn deref_mut(&mut self) -> &mut [E] {
        &mut self.0
    }
}

/// A fixed-size array of a workspace, read as a slice: [`Array`] of any length.
pub trait ArrayStorage<E>: Deref<Target = [E]> + DerefMut + Copy + Debug + PartialEq {
    /// Every element `e`.
    fn filled(e: E) -> Self;
    /// The elements of an uninitialised array, each to initialise in place.
    fn elements(place: &mut MaybeUninit<Self>) -> &mut [MaybeUninit<E>];
}

impl<E: Copy + Debug + PartialEq, const N: usize> ArrayStorage<E> for Array<E, N> {
    fn filled(e: E) -> Self {
        Array([e; N])
    }
    fn elements(place: &mut MaybeUninit<Self>) -> &mut [MaybeUninit<E>] {
        // SAFETY: `Array<E, N>` is `repr(transparent)` over `[E; N]`, whose layout is
        // that of `[MaybeUninit<E>; N]`, and every bit pattern (initialised or not) is
        // a valid value of the latter.
        unsafe { &mut *(place as *mut MaybeUninit<Self>).cast::<[MaybeUninit<E>; N]>() }
    }
}

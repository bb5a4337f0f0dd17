//! [`ModelBuilder`]: a model declared link by link, group by group, then validated
//! (the checks of `validate.rs`): its own, or one rebuilt in place.

use super::validate::{validate, validate_rebuilt};
use super::{
    default_gravity, default_singular_tol, Drive, GroupSpec, Link, Load, Model, Points, WriteGroup,
};
use crate::capacity::{Capacity, List};
use crate::error::ModelError;
use crate::motor::Motor;
use crate::scalar::{Real, Vec2};
use crate::structomat::{Group, PointRef};
use core::marker::PhantomData;
use core::ops::{Deref, DerefMut};

/// Builds and validates a [`Model`]: its own ([`ModelBuilder::new`], then
/// [`ModelBuilder::build`]) or one rebuilt in place ([`ModelBuilder::in_place`], then
/// [`ModelBuilder::finish`]), which keeps the model (16 KB in f64) off the stack.
#[derive(Clone, Debug)]
pub struct ModelBuilder<T: Real, M = OwnedModel<T>> {
    m: M,
    scalar: PhantomData<T>,
}

/// The model a [`ModelBuilder::new`] owns.
#[derive(Clone, Debug)]
pub struct OwnedModel<T: Real>(Model<T>);

impl<T: Real> Deref for OwnedModel<T> {
    type Target = Model<T>;
    fn deref(&self) -> &Model<T> {
        &self.0
    }
}

impl<T: Real> DerefMut for OwnedModel<T> {
    fn deref_mut(&mut self) -> &mut Model<T> {
        &mut self.0
    }
}

impl<T: Real> Default for ModelBuilder<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real> ModelBuilder<T> {
    /// An empty mechanism with gravity `(0, -9.81)` m/s² (SPEC: g along -y).
    pub fn new() -> Self {
        ModelBuilder {
            m: OwnedModel(Model::empty()),
            scalar: PhantomData,
        }
    }

    /// Validates the description and returns the model.
    pub fn build(mut self) -> Result<Model<T>, ModelError> {
        validate(&mut self.m)?;
        Ok(self.m.0)
    }
}

impl<'a, T: Real, C: Capacity<T>> ModelBuilder<T, &'a mut Model<T, C>> {
    /// Rebuilds `model` in place: empties it to the state of [`ModelBuilder::new`]'s
    /// model, then declares into it. Until [`ModelBuilder::finish`] succeeds, `model`
    /// is not a valid model.
    pub fn in_place(model: &'a mut Model<T, C>) -> Self {
        model.ground.clear();
        model.links.clear();
        model.groups.clear();
        model.drives.clear();
        model.loads.clear();
        model.gravity = default_gravity();
        model.dof = 0;
        model.singular_tol = default_singular_tol();
        model.newton_tol = T::zero();
        ModelBuilder {
            m: model,
            scalar: PhantomData,
        }
    }

    /// Validates the model built in place.
    pub fn finish(self) -> Result<(), ModelError> {
        validate(self.m)
    }

    /// [`ModelBuilder::finish`] for a model whose sequence of `dof` coordinates is
    /// known to be valid and whose groups were written by the crate's constructors of
    /// the motor element R, the dyad RRR, the triad and the Assur group from points
    /// only (their angle offsets zero): the converter's modes, rebuilt at each event,
    /// whose every declaration the full validation passes in the tests. It skips what
    /// only a wrong declaration could fail (see `validate_rebuilt`).
    pub(crate) fn finish_rebuilt(self, dof: u8) -> Result<(), ModelError> {
        validate_rebuilt(self.m, dof)
    }
}

impl<T: Real, M: DerefMut<Target = Model<T>>> ModelBuilder<T, M> {
    /// Appends a group to the motion-transmission sequence. [`ModelBuilder::build`]
    /// checks that every value the group holds is finite: its angle offsets and guesses
    /// as given, and what its constructor derives from the links' points (lengths,
    /// directions: a point at 1e200 m is finite but its squared length is not).
    pub fn group(&mut self, spec: &impl GroupSpec<T>) -> Result<u8, ModelError> {
        let g = spec.build(&self.m)?;
        self.m
            .groups
            .push(g)
            .map_err(|_| ModelError::Capacity("groups"))?;
        Ok((self.m.groups.len() - 1) as u8)
    }
}

impl<T: Real, C: Capacity<T>, M: DerefMut<Target = Model<T, C>>> ModelBuilder<T, M> {
    /// The model as declared so far (group constructors resolve points in it).
    pub fn model(&self) -> &Model<T, C> {
        &self.m
    }

    /// Sets gravity, m/s².
    pub fn gravity(&mut self, g: Vec2<T>) -> &mut Self {
        self.m.gravity = g;
        self
    }

    /// Sets the singularity threshold on a group's normalized determinant.
    pub fn singular_tol(&mut self, tol: T) -> &mut Self {
        self.m.singular_tol = tol;
        self
    }

    /// Adds a ground point (world, m).
    pub fn ground_point(&mut self, x: T, y: T) -> Result<PointRef, ModelError> {
        self.m
            .ground
            .push(Vec2::new(x, y))
            .map_err(|_| ModelError::Capacity("ground points"))?;
        Ok(PointRef {
            body: 0,
            point: (self.m.ground.len() - 1) as u8,
        })
    }

    /// Adds a moving link; returns its body index (1, 2, ...).
    pub fn link(&mut self, link: Link<T>) -> Result<u8, ModelError> {
        self.m
            .links
            .push(link)
            .map_err(|_| ModelError::Capacity("links"))?;
        Ok(self.m.links.len() as u8)
    }

    /// [`ModelBuilder::group`] for the constructors that write their group in place:
    /// the same group and errors (but a full sequence's, which comes first), the group
    /// written into the sequence, not built apart and moved there.
    pub(crate) fn group_in_place(&mut self, spec: &impl WriteGroup<T>) -> Result<u8, ModelError> {
        let Model {
            ground,
            links,
            groups,
            ..
        } = &mut *self.m;
        let points = Points { ground, links };
        if groups.is_full() {
            // Unlike `group`, before the constructor's own errors: its group would have
            // to be written apart (2 KB in f64 on the stack, and code of its own).
            return Err(ModelError::Capacity("groups"));
        }
        let _ = groups.push(Group::empty());
        let written = match groups.last_mut() {
            Some(g) => spec.write(&points, g),
            None => Err(ModelError::Capacity("groups")),
        };
        if let Err(e) = written {
            groups.pop();
            return Err(e);
        }
        Ok((groups.len() - 1) as u8)
    }

    /// Puts a motor on coordinate `coord` (applied by its first motor element).
    pub fn drive(&mut self, coord: u8, motor: Motor<T>) -> Result<&mut Self, ModelError> {
        self.m
            .drives
            .push(Drive {
                coord,
                group: u8::MAX,
                motor,
                joint: None,
            })
            .map_err(|_| ModelError::Capacity("drives"))?;
        Ok(self)
    }

    /// Puts a motor across the joint between link `body` and body `on` (a revolute or
    /// prismatic joint of the group that places `body`, `body` its moving side): its
    /// torque acts on `body` (reaction on `on`), or its force along the guide of `on`.
    /// The joint is found at validation.
    pub fn drive_across(
        &mut self,
        body: u8,
        on: u8,
        motor: Motor<T>,
    ) -> Result<&mut Self, ModelError> {
        self.m
            .drives
            .push(Drive {
                coord: Drive::<T>::ACROSS,
                // Resolved by validation: the bodies until then.
                group: body,
                motor,
                joint: Some(on),
            })
            .map_err(|_| ModelError::Capacity("drives"))?;
        Ok(self)
    }

    /// Adds a constant external load.
    pub fn load(&mut self, load: Load<T>) -> Result<&mut Self, ModelError> {
        self.m
            .loads
            .push(load)
            .map_err(|_| ModelError::Capacity("loads"))?;
        Ok(self)
    }
}

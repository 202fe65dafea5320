//! The fixes' residuals as the fits' one solve loop takes them
//! ([`super::fit::levenberg_marquardt`]): whitened under the noise ([`super::fix_noise`]),
//! in the free terms, each trial step held within any installation's limits. In: the
//! residuals and their Jacobian in the terms, the whitening and the terms free. Out:
//! the terms solved, or the error a residual met.

use crate::installation::estimate::fix_noise::Whitening;
use crate::installation::estimate::fix_terms::FixFitError;
use levenberg_marquardt::LeastSquaresProblem;
use nalgebra::storage::Owned;
use nalgebra::{DMatrix, DVector, Dyn};
use std::cell::RefCell;

/// The fixes' whitened residuals in the free terms, as the solve loop takes them: the
/// terms a trial step takes beyond any installation's limits held at them, and the
/// first error a residual met kept to be returned.
pub(super) struct Whitened<'p> {
    residuals: &'p Residuals<'p>,
    jacobian: &'p Jacobian<'p>,
    limits: Vec<f64>,
    whitening: &'p Whitening,
    free: &'p [bool],
    pub(super) terms: Vec<f64>,
    pub(super) failed: RefCell<Option<FixFitError>>,
}

/// The residuals at some terms.
pub(super) type Residuals<'p> = dyn Fn(&[f64]) -> Result<Vec<f64>, FixFitError> + 'p;

/// The residuals' Jacobian at some terms in the free ones, a column per free term.
pub(super) type Jacobian<'p> = dyn Fn(&[f64], &[bool]) -> Result<Vec<Vec<f64>>, FixFitError> + 'p;

impl<'p> Whitened<'p> {
    /// The fit of the `free` terms from `terms` to `residuals` (with their `jacobian`),
    /// under `whitening`, each term within its limit (`limits`, in magnitude).
    pub(super) fn new(
        (residuals, jacobian): (&'p Residuals<'p>, &'p Jacobian<'p>),
        limits: Vec<f64>,
        whitening: &'p Whitening,
        free: &'p [bool],
        terms: Vec<f64>,
    ) -> Self {
        Whitened {
            residuals,
            jacobian,
            limits,
            whitening,
            free,
            terms,
            failed: RefCell::new(None),
        }
    }

    fn free_terms(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.free.len()).filter(|&k| self.free[k])
    }

    /// `value`, or nothing with its error kept.
    fn kept<T>(&self, value: Result<T, FixFitError>) -> Option<T> {
        value
            .map_err(|error| *self.failed.borrow_mut() = Some(error))
            .ok()
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Whitened<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, parameters: &DVector<f64>) {
        let free: Vec<usize> = self.free_terms().collect();
        for (column, k) in free.into_iter().enumerate() {
            self.terms[k] = parameters[column].clamp(-self.limits[k], self.limits[k]);
        }
    }

    fn params(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.free.iter().filter(|&&f| f).count(),
            self.free_terms().map(|k| self.terms[k]),
        )
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let residuals = self.kept((self.residuals)(&self.terms))?;
        Some(DVector::from_vec(self.whitening.whiten(&residuals)))
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let columns = self.kept((self.jacobian)(&self.terms, self.free))?;
        let whitened: Vec<DVector<f64>> = (columns.iter())
            .map(|column| DVector::from_vec(self.whitening.whiten(column)))
            .collect();
        Some(DMatrix::from_columns(&whitened))
    }
}

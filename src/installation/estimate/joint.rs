//! One calibration over several recordings of the same vehicle: the vehicle's terms
//! (scale, misalignment, lever arm, and the bias unless it is the dive's) shared, the
//! dive's terms (its time offset, and the bias where asked) one set per recording.
//!
//! It starts from one installation (a recording's fit alone): the vehicle's terms as
//! it has them, each recording's clock from the search of [`search_offset`] about its
//! time offset with them held, as far as a dive's clock may be ([`starts_from`]). Then Levenberg–Marquardt on the normal equations, whose
//! structure is known: the vehicle's block A and each recording's block B_k, so the
//! recordings' terms are eliminated by a Schur complement,
//! `S = Σ_k A_kᵀ A_k − A_kᵀ B_k (B_kᵀ B_k)⁻¹ B_kᵀ A_k`, and K recordings cost K times one.
//! Each recording's samples are those of its own fit's fixed mask. As the single fit
//! does, it goes on from the least-squares solution under Huber's loss, then Tukey's
//! ([`super::robust`]), their scales per axis from the residuals of all the recordings
//! (one DVL): each residual and its Jacobian rows go through the loss's transform, so
//! the same Schur step minimises the robust cost.
//!
//! The vehicle's standard deviations are the single fit's [`bound`] applied to the
//! stacked Jacobian with the dive's terms projected out, `Ã_k = A_k − B_k (B_kᵀB_k)⁻¹
//! B_kᵀ A_k` (ÃᵀÃ is S): the same sandwich over the residuals' noise, read from all the
//! recordings. Each clock's is its own block's given the vehicle's (the same sandwich,
//! on its own residuals), plus the vehicle's uncertainty carried through
//! `(B_kᵀB_k)⁻¹ B_kᵀA_k`. Under the robust loss every product carries its weights D,
//! the bread's: `Ã_k = A_k − B_k (B_kᵀDB_k)⁻¹ B_kᵀDA_k`, the residuals the
//! pseudo-residuals.
//!
//! Each recording's own estimate of the vehicle's terms is one Gauss–Newton step from
//! the joint solution on its samples alone, its dive terms free: θ_k = θ − (Ã_kᵀDÃ_k)⁺
//! Ã_kᵀψ_k, whose information-weighted mean is θ itself; its standard deviations the
//! same bound over its samples, their residuals taken at θ_k. From them
//! [`super::between_dives`] reads how far each term moves between dives.
//! In: the recordings and their references, the vehicle's and the dive's terms. Out: a
//! [`JointFit`].

use crate::Vec3;
use crate::installation::estimate::between_dives::{BetweenDives, between_dives};
use crate::installation::estimate::bound::{
    Noise, TermBound, Tolerances, bound, gauss_newton_step,
};
use crate::installation::estimate::clock::{covariance, search_offset};
use crate::installation::estimate::fit::{
    Fit, FitError, TIME_OFFSET_MARGIN_S, beyond_any_installation, linearised, mask_about,
    residual_rms,
};
use crate::installation::estimate::robust::{Loss, Robust, RobustFit, scales};
use crate::installation::frames::Reference;
use crate::installation::terms::{Installation, TermSet};
use nalgebra::{DMatrix, DVector};

/// One recording of a joint calibration.
#[derive(Debug, Clone, Copy)]
pub struct JointRecording<'a> {
    pub time_s: &'a [f64],
    pub dvl_m_s: &'a [Vec3],
    pub reference: &'a Reference,
}

/// The most iterations of Levenberg–Marquardt.
const ITERATIONS: usize = 200;

/// The relative change of the cost under which the iterations stop.
const TOLERANCE: f64 = 1e-12;

/// A joint calibration.
#[derive(Debug, Clone)]
pub struct JointFit {
    pub vehicle_terms: TermSet,
    pub dive_terms: TermSet,
    /// The vehicle's terms (the dive's zero).
    pub vehicle: Installation,
    /// Each recording's installation: the vehicle's terms with its own dive terms.
    pub dives: Vec<Installation>,
    /// The vehicle's terms' standard deviations, correlations, what cannot be seen.
    pub bound: TermBound,
    /// Each recording's dive terms' standard deviations, in the order of
    /// [`TermSet::parameter_names`] of `dive_terms`.
    pub dive_std: Vec<Vec<f64>>,
    /// Each recording's residual RMS per DVL axis, m/s, and samples fitted.
    pub residual_rms_m_s: Vec<Vec3>,
    pub sample_counts: Vec<usize>,
    /// Each recording's samples the robust loss rejected as outliers.
    pub outliers: Vec<usize>,
    /// Each recording's own estimate of the vehicle's terms (its dive terms free), with
    /// its standard deviations, in the order of `bound`'s names.
    pub own: Vec<TermBound>,
    /// Each vehicle term's spread between the recordings, in the order of `bound`'s
    /// names; `None` where fewer than three recordings show it.
    pub between: Vec<Option<BetweenDives>>,
}

impl JointFit {
    /// The mean over the recordings of their dive terms, in the order of
    /// [`TermSet::parameter_names`] of `dive_terms`: what a recording with no clock of
    /// its own carries.
    pub fn mean_dive(&self) -> Vec<f64> {
        let per_dive: Vec<Vec<f64>> = self
            .dives
            .iter()
            .map(|d| d.to_parameters(&self.dive_terms))
            .collect();
        (0..self.dive_terms.parameter_count())
            .map(|k| per_dive.iter().map(|p| p[k]).sum::<f64>() / per_dive.len() as f64)
            .collect()
    }
}

/// Each recording's blocks at the current terms: residuals r, the vehicle's columns A
/// and the dive's B, through the robust loss's transform where there is one.
struct Blocks {
    /// v_dvl − predict, m/s, before any transform.
    raw: DVector<f64>,
    residuals: DVector<f64>,
    vehicle: DMatrix<f64>,
    dive: DMatrix<f64>,
    /// Whether each sample follows the one before it within a piece.
    follows: Vec<bool>,
}

impl Blocks {
    /// The residuals and Jacobian rows under `robust`'s loss: each residual its
    /// transform, each row times the transform's slope (as the single fit's).
    fn transform(&mut self, robust: Robust) {
        for (i, &r) in self.raw.iter().enumerate() {
            let (axis, u) = (i % 3, robust.scaled(r, i % 3));
            self.residuals[i] = robust.loss.residual(u, robust.scale_m_s[axis]);
            let slope = robust.loss.slope(u);
            self.vehicle.row_mut(i).scale_mut(slope);
            self.dive.row_mut(i).scale_mut(slope);
        }
    }
}

/// The vehicle's and the dive's terms of `terms`: the dive's are `dive`'s that `terms`
/// holds.
pub fn split(terms: TermSet, dive: TermSet) -> (TermSet, TermSet) {
    let dive_terms = TermSet {
        scale: crate::installation::terms::PerAxis::Off,
        misalignment: false,
        lever_arm: false,
        time_offset: terms.time_offset && dive.time_offset,
        bias: if dive.bias != crate::installation::terms::PerAxis::Off {
            terms.bias
        } else {
            crate::installation::terms::PerAxis::Off
        },
    };
    let vehicle_terms = TermSet {
        time_offset: terms.time_offset && !dive_terms.time_offset,
        bias: if dive_terms.bias == crate::installation::terms::PerAxis::Off {
            terms.bias
        } else {
            crate::installation::terms::PerAxis::Off
        },
        ..terms
    };
    (vehicle_terms, dive_terms)
}

/// The starts of a joint fit from `installation`: its terms, with each recording's time
/// offset the best of the search within ±`search_s` of its own (each recording's clock
/// may be far from it).
pub fn starts_from(
    recordings: &[JointRecording],
    installation: Installation,
    search_s: f64,
) -> Vec<Installation> {
    recordings
        .iter()
        .map(|r| {
            let searched =
                search_offset((r.time_s, r.dvl_m_s), r.reference, installation, search_s);
            Installation {
                time_offset_s: searched.map_or(installation.time_offset_s, |(tau, _)| tau),
                ..installation
            }
        })
        .collect()
}

/// The problem a joint fit solves: the recordings, each one's fixed samples (its fit's
/// mask about its start's clock), and which terms are the vehicle's and the dive's.
struct Problem<'a> {
    recordings: &'a [JointRecording<'a>],
    masks: Vec<std::ops::Range<usize>>,
    vehicle_terms: TermSet,
    dive_terms: TermSet,
    /// The robust loss minimised, where not least squares.
    robust: Option<Robust>,
}

/// The parameters of a joint fit: the vehicle's, and each recording's dive terms.
#[derive(Clone)]
struct Parameters {
    vehicle: DVector<f64>,
    dives: Vec<DVector<f64>>,
}

impl Problem<'_> {
    /// The installation of one recording: the vehicle's terms with its own.
    fn installation(&self, vehicle: &DVector<f64>, dive: &DVector<f64>) -> Installation {
        Installation::default()
            .with_parameters(&self.vehicle_terms, vehicle.as_slice())
            .with_parameters(&self.dive_terms, dive.as_slice())
    }

    /// Each recording's residuals and Jacobian blocks at `at`.
    fn blocks(&self, at: &Parameters) -> Vec<Blocks> {
        self.recordings
            .iter()
            .zip(&self.masks)
            .zip(&at.dives)
            .map(|((r, mask), dive)| {
                let installation = self.installation(&at.vehicle, dive);
                let (time_s, dvl_m_s) = (&r.time_s[mask.clone()], &r.dvl_m_s[mask.clone()]);
                let (residuals, vehicle) = linearised(
                    time_s,
                    dvl_m_s,
                    r.reference,
                    self.vehicle_terms,
                    installation,
                );
                let (_, dive) =
                    linearised(time_s, dvl_m_s, r.reference, self.dive_terms, installation);
                let mut blocks = Blocks {
                    raw: residuals.clone(),
                    residuals,
                    vehicle,
                    dive,
                    follows: r.reference.follows(time_s),
                };
                if let Some(robust) = self.robust {
                    blocks.transform(robust);
                }
                blocks
            })
            .collect()
    }

    /// The least-squares solution from `start`, then, as the single fit's, the
    /// solution under Huber's loss and Tukey's from it, each with the scales of the
    /// residuals it starts from (all the recordings': one DVL); `self.robust` is left
    /// at the last loss (none where the residuals have no scale).
    fn solve(&mut self, start: Parameters) -> Parameters {
        let (mut solution, mut blocks) = self.minimise(start);
        for loss in [Loss::Huber, Loss::TUKEY] {
            let raw = stack(blocks.iter().map(|b| &b.raw));
            let Some(scale_m_s) = scales(&raw) else {
                break;
            };
            self.robust = Some(Robust { loss, scale_m_s });
            (solution, blocks) = self.minimise(solution);
        }
        solution
    }

    /// Levenberg–Marquardt from `start`, each step through [`schur_step`]: the
    /// parameters at the least cost and their blocks.
    fn minimise(&self, start: Parameters) -> (Parameters, Vec<Blocks>) {
        let cost = |blocks: &[Blocks]| {
            blocks
                .iter()
                .map(|b| b.residuals.norm_squared())
                .sum::<f64>()
        };
        let (mut at, mut current) = (start.clone(), self.blocks(&start));
        let mut damping = 1e-3;
        for _ in 0..ITERATIONS {
            let before = cost(&current);
            let Some((step, dive_steps)) = schur_step(&current, damping) else {
                break;
            };
            let trial = Parameters {
                vehicle: &at.vehicle + &step,
                dives: at
                    .dives
                    .iter()
                    .zip(&dive_steps)
                    .map(|(d, s)| d + s)
                    .collect(),
            };
            let blocks = self.blocks(&trial);
            let after = cost(&blocks);
            if after <= before {
                (at, current) = (trial, blocks);
                damping = (damping / 3.0).max(1e-12);
                if before - after <= TOLERANCE * before {
                    break;
                }
            } else {
                damping *= 4.0;
                if damping > 1e12 {
                    break;
                }
            }
        }
        (at, current)
    }
}

/// Fits `terms` over every recording jointly, those of `dive` one set per recording,
/// from `starts` (one installation per recording, [`starts_from`]'s: the vehicle's
/// terms start at their mean); the bound from `noise`, the flags from `tolerances`.
pub fn joint_fit(
    recordings: &[JointRecording],
    starts: &[Installation],
    (terms, dive): (TermSet, TermSet),
    (noise, tolerances): (Noise, &Tolerances),
) -> Result<JointFit, FitError> {
    let (vehicle_terms, dive_terms) = split(terms, dive);
    let masks: Vec<_> = recordings
        .iter()
        .zip(starts)
        .map(|(r, start)| mask_about(r.time_s, r.reference, start.time_offset_s))
        .collect();
    let parameters = dive_terms.parameter_count();
    enough_samples(&masks, parameters)?;
    let mut problem = Problem {
        recordings,
        masks,
        vehicle_terms,
        dive_terms,
        robust: None,
    };
    let of = |start: &Installation| DVector::from_vec(start.to_parameters(&vehicle_terms));
    let start = Parameters {
        vehicle: starts.iter().map(of).sum::<DVector<f64>>() / starts.len() as f64,
        dives: starts
            .iter()
            .map(|start| DVector::from_vec(start.to_parameters(&dive_terms)))
            .collect(),
    };
    let solution = problem.solve(start);
    // The bound reads the raw Jacobian blocks, the loss's weights D apart.
    let robust = problem.robust.take();
    let blocks = problem.blocks(&solution);
    let (fitted, outliers) = robust_fits(&blocks, robust)?;
    let all_outliers = outliers.iter().sum::<usize>();
    let weighed: Vec<Weighed> = blocks
        .iter()
        .zip(&fitted)
        .map(|(b, f)| Weighed::of(b, f.as_ref()))
        .collect();
    let vehicle = problem.installation(&solution.vehicle, &DVector::zeros(parameters));
    let dives: Vec<Installation> = (solution.dives.iter())
        .map(|d| problem.installation(&solution.vehicle, d))
        .collect();
    if let Some(fault) = dives.iter().find_map(beyond_any_installation) {
        return Err(fault);
    }
    let stacked = stacked_fit(&weighed, vehicle_terms, vehicle, robust, all_outliers);
    let bound = bound(&stacked, noise, tolerances);
    let own: Vec<TermBound> = (weighed.iter().zip(&fitted))
        .map(|(w, f)| own_estimate(w, f.as_ref(), (vehicle_terms, vehicle), (noise, tolerances)))
        .collect();
    let between = spread_of(&own, bound.names.len());
    Ok(JointFit {
        own,
        between,
        vehicle_terms,
        dive_terms,
        vehicle,
        dives,
        dive_std: dive_standard_deviations(
            &weighed,
            &fitted,
            &bound,
            dive_terms,
            (noise, tolerances),
        ),
        bound,
        residual_rms_m_s: (blocks.iter())
            .map(|b| residual_rms(&b.raw, b.raw.len() / 3))
            .collect(),
        sample_counts: blocks.iter().map(|b| b.raw.len() / 3).collect(),
        outliers,
    })
}

/// Refuses recordings of which one has no more samples in its mask (`masks`) than its
/// `parameters` dive terms can fit.
fn enough_samples(masks: &[std::ops::Range<usize>], parameters: usize) -> Result<(), FitError> {
    match masks
        .iter()
        .map(|m| m.len())
        .find(|&n| 3 * n <= parameters + 1)
    {
        Some(usable) => Err(FitError::TooFewSamples {
            usable,
            parameters,
            margin_s: TIME_OFFSET_MARGIN_S,
        }),
        None => Ok(()),
    }
}

/// What `robust`'s loss makes of each recording's raw residuals (none under least
/// squares), and each one's outliers; refused where more than a quarter of all the
/// samples are outliers.
fn robust_fits(
    blocks: &[Blocks],
    robust: Option<Robust>,
) -> Result<(Vec<Option<RobustFit>>, Vec<usize>), FitError> {
    let fitted: Vec<Option<RobustFit>> = (blocks.iter())
        .map(|b| robust.map(|r| r.fitted(&b.raw)))
        .collect();
    let outliers: Vec<usize> = (fitted.iter())
        .map(|f| f.as_ref().map_or(0, |f| f.outliers))
        .collect();
    let samples: usize = blocks.iter().map(|b| b.raw.len() / 3).sum();
    let all = outliers.iter().sum::<usize>();
    if 4 * all > samples {
        return Err(FitError::Outliers {
            outliers: all,
            samples,
        });
    }
    Ok((fitted, outliers))
}

/// The vehicle's terms `vehicle` as one fit over every recording's samples, for the
/// single fit's [`bound`]: the stacked Jacobian with the dive's terms projected out,
/// the meat's residuals, and under a robust loss its weights D and `outliers`.
fn stacked_fit(
    weighed: &[Weighed],
    terms: TermSet,
    vehicle: Installation,
    robust: Option<Robust>,
    outliers: usize,
) -> Fit {
    let (jacobian, residuals, follows) = projected(weighed);
    Fit {
        terms,
        installation: vehicle,
        parameters: vehicle.to_parameters(&terms),
        residual_rms_m_s: [0.0; 3],
        sample_count: residuals.len() / 3,
        mask_centre_s: None,
        jacobian,
        residuals,
        robust: robust.map(|loss| RobustFit {
            loss,
            curvature: stack(weighed.iter().map(|w| &w.curvature)),
            outliers,
        }),
        follows,
        termination: "joint".into(),
    }
}

/// One recording's raw blocks as the bound reads them under a loss: its bread's
/// weights D, its residuals as the meat reads them (the pseudo-residuals), and the
/// dive's normal matrix BᵀDB inverted (`None` where singular).
struct Weighed<'a> {
    blocks: &'a Blocks,
    curvature: DVector<f64>,
    meat: DVector<f64>,
    dive_inverse: Option<DMatrix<f64>>,
}

impl<'a> Weighed<'a> {
    fn of(blocks: &'a Blocks, fitted: Option<&RobustFit>) -> Weighed<'a> {
        let curvature = fitted.map_or_else(
            || DVector::from_element(blocks.raw.len(), 1.0),
            |f| f.curvature.clone(),
        );
        let meat = fitted.map_or_else(
            || blocks.raw.clone(),
            |f| f.loss.pseudo_residuals(&blocks.raw),
        );
        let dive_inverse =
            (blocks.dive.transpose() * weighted(&curvature, &blocks.dive)).try_inverse();
        Weighed {
            blocks,
            curvature,
            meat,
            dive_inverse,
        }
    }

    /// (BᵀDB)⁻¹ BᵀDA: how the dive's terms follow the vehicle's.
    fn gain(&self) -> Option<DMatrix<f64>> {
        let b = self.blocks;
        let inverse = self.dive_inverse.as_ref()?;
        Some(inverse * (b.dive.transpose() * weighted(&self.curvature, &b.vehicle)))
    }

    /// This recording's samples as a fit of `terms` at `at` whose Jacobian is
    /// `jacobian` (some of its columns), for the single fit's [`bound`]: its residuals as
    /// the meat reads them, `fitted`'s loss, its pieces.
    fn fit(
        &self,
        (terms, at): (TermSet, Installation),
        jacobian: DMatrix<f64>,
        fitted: Option<&RobustFit>,
    ) -> Fit {
        Fit {
            terms,
            installation: at,
            parameters: at.to_parameters(&terms),
            residual_rms_m_s: [0.0; 3],
            sample_count: self.blocks.raw.len() / 3,
            mask_centre_s: None,
            jacobian,
            residuals: self.meat.clone(),
            robust: fitted.cloned(),
            follows: self.blocks.follows.clone(),
            termination: "joint".into(),
        }
    }

    /// The vehicle's columns with the dive's terms projected out (in the D-metric),
    /// Ã = A − B (BᵀDB)⁻¹ BᵀDA; A itself where the dive has no terms or they are not
    /// seen.
    fn projected_vehicle(&self) -> DMatrix<f64> {
        let b = self.blocks;
        match self.gain() {
            Some(gain) if b.dive.ncols() > 0 => &b.vehicle - &b.dive * gain,
            _ => b.vehicle.clone(),
        }
    }
}

/// Each of the `terms` vehicle terms' spread between the recordings, from their `own`
/// estimates.
fn spread_of(own: &[TermBound], terms: usize) -> Vec<Option<BetweenDives>> {
    (0..terms)
        .map(|j| {
            let each: Vec<(f64, f64)> = own.iter().map(|o| (o.value[j], o.std[j])).collect();
            between_dives(&each)
        })
        .collect()
}

/// One recording's own estimate of the vehicle's terms, from `vehicle` (the joint
/// solution of `terms`): one Gauss–Newton step on its samples alone with its dive terms
/// projected out, under the loss's weights, and its bound there, the residuals (the
/// pseudo-residuals ψ, as the meat reads them) carried to the step, ψ + D Ã δ.
fn own_estimate(
    w: &Weighed,
    fitted: Option<&RobustFit>,
    (terms, vehicle): (TermSet, Installation),
    (noise, tolerances): (Noise, &Tolerances),
) -> TermBound {
    let at = vehicle.to_parameters(&terms);
    let mut own = w.fit((terms, vehicle), w.projected_vehicle(), fitted);
    let step = gauss_newton_step(&own);
    let moved = &own.jacobian * &step;
    for (i, r) in own.residuals.iter_mut().enumerate() {
        *r += w.curvature[i] * moved[i];
    }
    own.parameters = at.iter().zip(step.iter()).map(|(a, d)| a + d).collect();
    own.installation = Installation::default().with_parameters(&terms, &own.parameters);
    bound(&own, noise, tolerances)
}

/// diag(`d`) · `m`: each row of `m` times its weight.
fn weighted(d: &DVector<f64>, m: &DMatrix<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| d[i] * m[(i, j)])
}

/// `parts` one after another.
fn stack<'a>(parts: impl Iterator<Item = &'a DVector<f64>> + Clone) -> DVector<f64> {
    let rows = parts.clone().map(|p| p.len()).sum();
    DVector::from_iterator(rows, parts.flat_map(|p| p.iter().copied()))
}

/// (B_kᵀB_k + λ diag)⁻¹ for each recording; `None` where one is singular.
fn dive_inverses(blocks: &[Blocks], damping: f64) -> Option<Vec<DMatrix<f64>>> {
    blocks
        .iter()
        .map(|b| {
            let mut normal = b.dive.transpose() * &b.dive;
            for k in 0..normal.nrows() {
                normal[(k, k)] *= 1.0 + damping;
            }
            normal.try_inverse()
        })
        .collect()
}

/// One damped Gauss–Newton step, the dive's blocks eliminated: the vehicle's step and
/// each recording's.
fn schur_step(blocks: &[Blocks], damping: f64) -> Option<(DVector<f64>, Vec<DVector<f64>>)> {
    let inverses = dive_inverses(blocks, damping)?;
    let p = blocks[0].vehicle.ncols();
    let mut schur = DMatrix::<f64>::zeros(p, p);
    let mut gradient = DVector::<f64>::zeros(p);
    for (b, inverse) in blocks.iter().zip(&inverses) {
        let cross = b.vehicle.transpose() * &b.dive;
        let dive_gradient = b.dive.transpose() * &b.residuals;
        schur += b.vehicle.transpose() * &b.vehicle - &cross * inverse * cross.transpose();
        gradient += b.vehicle.transpose() * &b.residuals - &cross * inverse * &dive_gradient;
    }
    for k in 0..p {
        schur[(k, k)] *= 1.0 + damping;
    }
    // The residual is v_dvl − predict and the Jacobian its derivative: the step is
    // −(JᵀJ)⁻¹ Jᵀ r.
    let step = match p {
        0 => DVector::zeros(0),
        _ => -schur.cholesky()?.solve(&gradient),
    };
    let dive_steps = blocks
        .iter()
        .zip(&inverses)
        .map(|(b, inverse)| {
            let right = b.dive.transpose() * (&b.residuals + &b.vehicle * &step);
            -(inverse * right)
        })
        .collect();
    Some((step, dive_steps))
}

/// The vehicle's Jacobian with each recording's dive terms projected out (in the
/// D-metric), stacked, and the meat's residuals and the pieces' neighbours stacked
/// likewise (no recording follows another).
fn projected(weighed: &[Weighed]) -> (DMatrix<f64>, DVector<f64>, Vec<bool>) {
    let rows: usize = weighed.iter().map(|w| w.meat.len()).sum();
    let p = weighed.first().map_or(0, |w| w.blocks.vehicle.ncols());
    let mut jacobian = DMatrix::zeros(rows, p);
    let mut at = 0;
    for w in weighed {
        let n = w.blocks.raw.len();
        jacobian.rows_mut(at, n).copy_from(&w.projected_vehicle());
        at += n;
    }
    let residuals = stack(weighed.iter().map(|w| &w.meat));
    let follows = weighed
        .iter()
        .flat_map(|w| w.blocks.follows.clone())
        .collect();
    (jacobian, residuals, follows)
}

/// Each recording's dive terms' standard deviations: its own block's given the
/// vehicle's terms (the single fit's [`bound`] on its residuals, their correlation in
/// time included, under the loss's weights), plus the vehicle's covariance carried
/// through (B_kᵀDB_k)⁻¹ B_kᵀDA_k.
fn dive_standard_deviations(
    weighed: &[Weighed],
    fitted: &[Option<RobustFit>],
    vehicle: &TermBound,
    dive_terms: TermSet,
    (noise, tolerances): (Noise, &Tolerances),
) -> Vec<Vec<f64>> {
    let covariance = covariance(&vehicle.std, &vehicle.correlation);
    weighed
        .iter()
        .zip(fitted)
        .map(|(w, fitted)| {
            let b = w.blocks;
            let Some(gain) = w.gain() else {
                return vec![f64::INFINITY; b.dive.ncols()];
            };
            let own = w.fit(
                (dive_terms, Installation::default()),
                b.dive.clone(),
                fitted.as_ref(),
            );
            let given = bound(&own, noise, tolerances).std;
            let carried = &gain * &covariance * gain.transpose();
            (0..b.dive.ncols())
                .map(|k| (given[k].powi(2) + carried[(k, k)]).sqrt())
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::estimate::bound::DEFAULT_TOLERANCES;
    use crate::installation::estimate::clock::tests::turning_dive;
    use crate::installation::terms::PerAxis;

    type Dive = (Vec<f64>, Vec<Vec3>, Reference);

    /// The noise of [`turning_dive`]'s DVL here, 1 cm/s per axis.
    const NOISE: Noise = Noise {
        dvl_m_s: 0.01,
        reference_m_s: 0.0,
    };

    /// `dives` of one vehicle fitted jointly in `terms`, each with its own clock, from
    /// the first one's fit alone; that fit beside it.
    fn fitted_jointly(dives: &[Dive], terms: TermSet) -> (JointFit, Fit) {
        let recordings: Vec<JointRecording> = dives
            .iter()
            .map(|(time_s, dvl_m_s, reference)| JointRecording {
                time_s,
                dvl_m_s,
                reference,
            })
            .collect();
        let clock = TermSet {
            time_offset: true,
            ..TermSet::NONE
        };
        let (time_s, dvl_m_s, reference) = &dives[0];
        let first =
            crate::installation::estimate::fit::fit(time_s, dvl_m_s, reference, terms).unwrap();
        let starts = starts_from(&recordings, first.installation, 30.0);
        let joint = joint_fit(
            &recordings,
            &starts,
            (terms, clock),
            (NOISE, &DEFAULT_TOLERANCES),
        )
        .unwrap();
        (joint, first)
    }

    /// Every vehicle term of `joint` within three standard deviations of `geometry`'s,
    /// and every clock of those of `clocks`.
    fn assert_covers(joint: &JointFit, geometry: &Installation, clocks: &[f64]) {
        let truth = geometry.to_parameters(&joint.vehicle_terms);
        for (k, name) in joint.bound.names.iter().enumerate() {
            let error = joint.bound.value[k] - truth[k];
            assert!(
                error.abs() < 3.0 * joint.bound.std[k],
                "{name}: {error} ± {}",
                joint.bound.std[k]
            );
        }
        for (k, &tau) in clocks.iter().enumerate() {
            let error = joint.dives[k].time_offset_s - tau;
            assert!(
                error.abs() < 3.0 * joint.dive_std[k][0],
                "clock {k}: {error} ± {}",
                joint.dive_std[k][0]
            );
        }
    }

    const GEOMETRY: Installation = Installation {
        scale: [0.0; 3],
        misalignment_rad: [0.0; 3],
        lever_arm_m: [-1.9, 0.05, 0.4],
        time_offset_s: 0.0,
        bias_m_s: [0.01, -0.005, 0.003],
    };

    const LEVER_OFFSET_BIAS: TermSet = TermSet {
        lever_arm: true,
        time_offset: true,
        bias: PerAxis::PerAxis,
        ..TermSet::NONE
    };

    #[test]
    fn the_joint_fit_recovers_the_shared_terms_and_every_clock() {
        let geometry = Installation {
            scale: [0.01; 3],
            ..GEOMETRY
        };
        let clocks = [0.6, -1.2, 2.1, 0.2];
        let dives: Vec<Dive> = (clocks.iter().enumerate())
            .map(|(k, &tau)| {
                let truth = Installation {
                    time_offset_s: tau,
                    ..geometry
                };
                turning_dive(&truth, 0.01, 30 + k as u64)
            })
            .collect();
        let terms = TermSet {
            scale: PerAxis::Scalar,
            ..LEVER_OFFSET_BIAS
        };
        let (joint, first) = fitted_jointly(&dives, terms);
        assert_covers(&joint, &geometry, &clocks);
        // Four recordings hold four times one's information: half its deviation.
        let alone = bound(&first, NOISE, &DEFAULT_TOLERANCES);
        let lever_x = |names: &[&str]| names.iter().position(|n| *n == "lever_arm_x_m").unwrap();
        let ratio = joint.bound.bound_std[lever_x(&joint.bound.names)]
            / alone.bound_std[lever_x(&alone.names)];
        assert!((0.4..0.6).contains(&ratio), "{ratio}");
    }

    #[test]
    fn spikes_in_every_recording_pull_nothing_and_are_counted() {
        // Three dives, 3 % of each one's samples with a 0.5 to 2 m/s spike on one axis.
        let clocks = [0.6, -1.2, 2.1];
        let mut spiked = Vec::new();
        let dives: Vec<Dive> = (clocks.iter().enumerate())
            .map(|(k, &tau)| {
                let truth = Installation {
                    time_offset_s: tau,
                    ..GEOMETRY
                };
                let (time_s, mut dvl, reference) = turning_dive(&truth, 0.01, 40 + k as u64);
                let mut count = 0;
                for i in (7..dvl.len()).step_by(33) {
                    dvl[i][i % 3] += 0.5 + 1.5 * ((i * 37) % 100) as f64 / 100.0;
                    count += 1;
                }
                spiked.push(count);
                (time_s, dvl, reference)
            })
            .collect();
        let (joint, _) = fitted_jointly(&dives, LEVER_OFFSET_BIAS);
        // Every spike is one of the fit's outliers (the samples its mask fits may lose a
        // spike at either end).
        for (k, (&outliers, &count)) in joint.outliers.iter().zip(&spiked).enumerate() {
            assert!(
                (count - 1..=count).contains(&outliers),
                "dive {k}: {outliers} of {count}"
            );
        }
        assert_covers(&joint, &GEOMETRY, &clocks);
        // The spikes cost nothing: each standard deviation within 1.5 of the noise's
        // bound.
        for (k, name) in joint.bound.names.iter().enumerate() {
            assert!(
                joint.bound.std[k] < 1.5 * joint.bound.bound_std[k],
                "{name}"
            );
        }
    }
}

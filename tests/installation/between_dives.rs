//! Intervals that hold on the next dive. Dives of one vehicle are simulated whose own
//! terms depart from the vehicle's (each dive's bias by N(0, 0.5 cm/s) and its lever arm
//! by N(0, 3 cm) per axis, where the terms vary) or share them exactly, each dive with
//! its own clock; a joint calibration of K of them (lever arm, time offset and bias, the
//! clock the dive's) states, per vehicle term, a 95 % interval of the vehicle's term and
//! one of a next dive's own fit ([`between_dives`]). Over the seeds, the first must hold
//! the vehicle's term and the second a left-out dive's own fit, 93–97 % of the time over
//! the six terms (each term's share printed).
//!
//! [`between_dives`]: dcnet_exp::installation::estimate::between_dives

use crate::coverage::{NOISE, segments, simulated, synthetic_segments};
use dcnet_exp::data::paired::PairedFiles;
use dcnet_exp::installation::estimate::bound::{DEFAULT_TOLERANCES, Noise};
use dcnet_exp::installation::estimate::fit::{fit, fit_about};
use dcnet_exp::installation::estimate::joint::{JointFit, JointRecording, joint_fit, starts_from};
use dcnet_exp::installation::study::Recording;
use dcnet_exp::installation::terms::{Installation, PerAxis, TermSet};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal, Uniform};
use rayon::prelude::*;

/// The vehicle's terms: the dives' mean.
const VEHICLE: Installation = Installation {
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

const CLOCK: TermSet = TermSet {
    time_offset: true,
    ..TermSet::NONE
};

/// How far a dive's own terms depart from the vehicle's, per axis (standard
/// deviations): its bias, m/s, and its lever arm, m.
#[derive(Debug, Clone, Copy)]
struct Departures {
    bias_m_s: f64,
    lever_arm_m: f64,
}

const SHARED: Departures = Departures {
    bias_m_s: 0.0,
    lever_arm_m: 0.0,
};

const VARYING: Departures = Departures {
    bias_m_s: 0.005,
    lever_arm_m: 0.03,
};

/// One dive: its stamps and DVL, and the trajectory it ran.
struct Dive<'a> {
    time_s: Vec<f64>,
    dvl: Vec<[f64; 3]>,
    segment: &'a Recording,
}

impl Dive<'_> {
    /// The dive as a joint fit (or its clock's search) takes it.
    fn recording(&self) -> JointRecording<'_> {
        JointRecording {
            time_s: &self.time_s,
            dvl_m_s: &self.dvl,
            reference: &self.segment.reference,
        }
    }
}

/// Dive `k` of seed `rng`'s draw: the vehicle's terms with `departures`, a clock
/// within ±5 s, white noise of 1 cm/s ([`NOISE`]), on trajectory `k % 4`.
fn dive<'a>(
    segments: &'a [Recording],
    k: usize,
    departures: Departures,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> Dive<'a> {
    let lever = Normal::new(0.0, departures.lever_arm_m).unwrap();
    let bias = Normal::new(0.0, departures.bias_m_s).unwrap();
    let truth = Installation {
        lever_arm_m: VEHICLE.lever_arm_m.map(|l| l + lever.sample(rng)),
        bias_m_s: VEHICLE.bias_m_s.map(|b| b + bias.sample(rng)),
        time_offset_s: 10.0 * (Uniform::new(0.0, 1.0).unwrap().sample(rng) - 0.5),
        ..VEHICLE
    };
    let segment = &segments[k % segments.len()];
    let (time_s, dvl) = simulated(segment, &truth, 0.0, rng);
    Dive {
        time_s,
        dvl,
        segment,
    }
}

/// The joint calibration of `dives`, started from the vehicle's terms off by a little
/// and no clock (the search finds each).
fn jointly(dives: &[Dive]) -> JointFit {
    let recordings: Vec<JointRecording> = dives.iter().map(Dive::recording).collect();
    let start = Installation {
        lever_arm_m: [-1.7, 0.0, 0.3],
        ..VEHICLE
    };
    let starts = starts_from(&recordings, start, 10.0);
    joint_fit(
        &recordings,
        &starts,
        (LEVER_OFFSET_BIAS, CLOCK),
        (NOISE, &DEFAULT_TOLERANCES),
    )
    .expect("a joint fit")
}

/// Per term, the share of `hits` (one row of the six terms per seed) that hold; and
/// over all six.
fn shares(hits: &[Vec<bool>]) -> (Vec<f64>, f64) {
    let seeds = hits.len() as f64;
    let per_term: Vec<f64> = (0..hits[0].len())
        .map(|j| hits.iter().filter(|h| h[j]).count() as f64 / seeds)
        .collect();
    let all = per_term.iter().sum::<f64>() / per_term.len() as f64;
    (per_term, all)
}

#[test]
fn the_joint_intervals_hold_the_vehicles_terms_at_three_five_and_ten_dives() {
    let (_dir, segments) = synthetic_segments();
    let mut outside = Vec::new();
    for (kind, departures) in [("shared", SHARED), ("varying", VARYING)] {
        for dives in [3, 5, 10] {
            let seeds: u64 = if dives == 10 { 200 } else { 400 };
            // Per seed, the random-effects intervals' hits, then the joint fit's own
            // (its noise alone, ±t σ).
            let both: Vec<(Vec<bool>, Vec<bool>)> = (0..seeds)
                .into_par_iter()
                .map(|seed| {
                    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
                    let drawn: Vec<Dive> = (0..dives)
                        .map(|k| dive(&segments, k + seed as usize, departures, &mut rng))
                        .collect();
                    let joint = jointly(&drawn);
                    let truth = VEHICLE.to_parameters(&joint.vehicle_terms);
                    let between = (joint.between.iter().zip(&truth))
                        .map(|(between, truth)| {
                            let (low, high) = between.expect("three dives or more").vehicle_95();
                            (low..=high).contains(truth)
                        })
                        .collect();
                    let noise_alone = (0..truth.len())
                        .map(|j| {
                            let error = joint.bound.value[j] - truth[j];
                            error.abs() <= joint.bound.half_width_95(j)
                        })
                        .collect();
                    (between, noise_alone)
                })
                .collect();
            let hits: Vec<Vec<bool>> = both.iter().map(|b| b.0.clone()).collect();
            let alone: Vec<Vec<bool>> = both.iter().map(|b| b.1.clone()).collect();
            let (per_term, all) = shares(&hits);
            println!(
                "{kind} terms, {dives} dives, {seeds} seeds: the vehicle's terms held {all:.3} (lever arm x, y, z, bias x, y, z: {per_term:.3?}); by the joint fit's own ±t σ {:.3}",
                shares(&alone).1
            );
            if !(0.93..=0.97).contains(&all) {
                outside.push(format!("{kind}, {dives} dives: {all:.3}"));
            }
        }
    }
    assert!(
        outside.is_empty(),
        "outside 93–97 %: {}",
        outside.join("; ")
    );
}

#[test]
fn the_next_dive_interval_holds_a_left_out_dives_own_fit() {
    let (_dir, segments) = synthetic_segments();
    let mut outside = Vec::new();
    for (kind, departures) in [("shared", SHARED), ("varying", VARYING)] {
        let hits: Vec<Vec<bool>> = (0..400u64)
            .into_par_iter()
            .map(|seed| {
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
                let mut drawn: Vec<Dive> = (0..6)
                    .map(|k| dive(&segments, k + seed as usize, departures, &mut rng))
                    .collect();
                let left_out = drawn.pop().expect("six dives");
                let joint = jointly(&drawn);
                // Its own fit, from the joint terms and its clock's search.
                let start = starts_from(&[left_out.recording()], joint.vehicle, 10.0)[0];
                let own = fit_about(
                    &left_out.time_s,
                    &left_out.dvl,
                    &left_out.segment.reference,
                    LEVER_OFFSET_BIAS,
                    start,
                )
                .expect("the left-out dive's own fit");
                let values = own.installation.to_parameters(&joint.vehicle_terms);
                (joint.between.iter().zip(&values))
                    .map(|(between, value)| {
                        let (low, high) = between.expect("three dives or more").next_dive_95();
                        (low..=high).contains(value)
                    })
                    .collect()
            })
            .collect();
        let (per_term, all) = shares(&hits);
        println!(
            "{kind} terms, five dives calibrated, a sixth left out, 400 seeds: its own fit within the next-dive interval {all:.3} (lever arm x, y, z, bias x, y, z: {per_term:.3?})"
        );
        if !(0.93..=0.97).contains(&all) {
            outside.push(format!("{kind}: {all:.3}"));
        }
    }
    assert!(
        outside.is_empty(),
        "outside 93–97 %: {}",
        outside.join("; ")
    );
}

/// The A-KIT segments that turn (T12 and T13 hold their heading).
const TURNING: usize = 11;

/// Every joint calibration of four turning A-KIT segments (lever arm, time offset and
/// bias, the clock each segment's own), its next-dive intervals checked against a fifth
/// turning segment's own fit: for each left-out segment, every four of the other ten
/// (2310 joint calibrations). The next-dive intervals must hold the left-out segment's
/// own lever arm and bias in at least 88 % of the cases over the six terms; one segment's
/// own interval held the next's 65 % of the time.
#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn on_akit_the_next_dive_interval_of_four_segments_holds_a_fifths_own_fit() {
    let akit = crate::common::akit();
    let files: Vec<PairedFiles> = (1..=TURNING).map(|n| PairedFiles::akit(&akit, n)).collect();
    let segments = segments(&files);
    let noise = Noise {
        dvl_m_s: 0.02,
        reference_m_s: 0.0,
    };
    let own: Vec<Installation> = segments
        .iter()
        .map(|s| {
            let r = &s.recording;
            fit(&r.time_s, &r.dvl_m_s, &s.reference, LEVER_OFFSET_BIAS)
                .expect("each turning segment's own fit")
                .installation
        })
        .collect();
    let mut cases: Vec<(usize, [usize; 4])> = Vec::new();
    for left_out in 0..TURNING {
        let others: Vec<usize> = (0..TURNING).filter(|&k| k != left_out).collect();
        for a in 0..others.len() {
            for b in a + 1..others.len() {
                for c in b + 1..others.len() {
                    for d in c + 1..others.len() {
                        cases.push((left_out, [others[a], others[b], others[c], others[d]]));
                    }
                }
            }
        }
    }
    let hits: Vec<Vec<bool>> = cases
        .par_iter()
        .map(|(left_out, four)| {
            let recordings: Vec<JointRecording> = four
                .iter()
                .map(|&k| JointRecording {
                    time_s: &segments[k].recording.time_s,
                    dvl_m_s: &segments[k].recording.dvl_m_s,
                    reference: &segments[k].reference,
                })
                .collect();
            let starts = starts_from(&recordings, own[four[0]], 30.0);
            let joint = joint_fit(
                &recordings,
                &starts,
                (LEVER_OFFSET_BIAS, CLOCK),
                (noise, &DEFAULT_TOLERANCES),
            )
            .expect("a joint fit of four turning segments");
            let values = own[*left_out].to_parameters(&joint.vehicle_terms);
            (joint.between.iter().zip(&values))
                .map(|(between, value)| {
                    let (low, high) = between
                        .expect("four segments show each term")
                        .next_dive_95();
                    (low..=high).contains(value)
                })
                .collect()
        })
        .collect();
    let (per_term, all) = shares(&hits);
    println!(
        "A-KIT, every ordered pair of the 13 segments: B's own fit within 1.96 √(σ_A² + σ_B²) of A's {:.3}; of the 11 turning ones {:.3}",
        one_dive_against_the_next(&akit, noise, 13),
        one_dive_against_the_next(&akit, noise, TURNING)
    );
    println!(
        "A-KIT, {} joint calibrations of four turning segments: a fifth's own fit within the next-dive interval {all:.3} (lever arm x, y, z, bias x, y, z: {per_term:.3?})",
        cases.len()
    );
    assert!(all >= 0.88, "{all:.3}");
}

/// Over every ordered pair (A, B) of the first `count` A-KIT segments, each fitted alone
/// (lever arm, time offset, bias), the share of B's lever arm and bias within
/// 1.96 √(σ_A² + σ_B²) of A's: one dive's interval against the next dive's own fit.
fn one_dive_against_the_next(akit: &std::path::Path, noise: Noise, count: usize) -> f64 {
    use dcnet_exp::installation::estimate::bound::bound;
    let files: Vec<PairedFiles> = (1..=count).map(|n| PairedFiles::akit(akit, n)).collect();
    let fitted: Vec<(Vec<f64>, Vec<f64>)> = segments(&files)
        .iter()
        .map(|s| {
            let r = &s.recording;
            let own = fit(&r.time_s, &r.dvl_m_s, &s.reference, LEVER_OFFSET_BIAS).expect("a fit");
            let bounded = bound(&own, noise, &DEFAULT_TOLERANCES);
            // Lever arm and bias: every parameter but the clock (the fourth).
            let keep = |v: &[f64]| [0, 1, 2, 4, 5, 6].map(|k| v[k]).to_vec();
            (keep(&own.parameters), keep(&bounded.std))
        })
        .collect();
    let mut hits = Vec::new();
    for (a, (value_a, std_a)) in fitted.iter().enumerate() {
        for (b, (value_b, std_b)) in fitted.iter().enumerate() {
            if a != b {
                hits.push(
                    (0..6)
                        .map(|j| (value_b[j] - value_a[j]).abs() <= 1.96 * std_a[j].hypot(std_b[j]))
                        .collect(),
                );
            }
        }
    }
    shares(&hits).1
}

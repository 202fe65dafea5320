//! `calibrate --fixes`: a DVL calibrated against position fixes and an attitude, for a
//! vehicle with no velocity reference, by one library call: the DVL beside the attitude
//! and the fixes are read ([`crate::data::fixes`]), the terms fitted to the fixes
//! through the dead reckoning ([`crate::installation::estimate::fixes`]), the fixes'
//! residual before and after, the recording written corrected (as `calibrate` writes
//! it), and the installation saved for `correct` as any other.
//! In: [`FixArgs`]. Out: a [`FixCalibration`], everything the command prints, or a
//! [`CalibrateError`] naming the argument, file or step at fault.

use crate::data::fixes::{FixColumns, Fixes, read_beside_attitude, read_fixes};
use crate::data::nmea::{LoggedFixes, gga_fixes, is_gga, is_nmea, read_nmea_fixes};
use crate::data::paired::Source;
use crate::data::paired::bag::{BagError, is_bag, read_bag_beside_attitude};
use crate::data::paired::dvl_log::{self, LogFormat, navigation_fixes, read_beside_own_attitude};
use crate::data::paired::read_log_beside_attitude;
use crate::data::paired::{PairedError, PairedRecording, ReadCounts, ReadRecording};
use crate::footprint::machine_memory;
use crate::installation::estimate::fixes::{
    DEFAULT_FIX_TERMS, FIX_LATENCY, FixFit, FixNoise, FixTerms, fit_fixes,
};
use crate::installation::fix_drift::Span;
use crate::installation::frames::{Attitude, Reference};
use crate::installation::terms::names::{TermName, term_set};
use crate::operator::calibrate::{CalibrateError, NOISE_RATIO_LIMIT, clear_of_inputs, named};
use crate::operator::cost::{Cost, FIXES, PerRow, Rows};
use crate::operator::fix_drifts::{BlackoutAsked, FixDrifts, drifts, withhold};
use crate::operator::inputs::{self, Reading, columns, fix_columns, source};
use crate::operator::installation_file::SavedInstallation;
use crate::results::ResultsError;
use crate::results::corrected::{Outputs, corrected_samples, stem, write};
use std::path::{Path, PathBuf};

/// The files a DVL is fitted to fixes from: the DVL's, the attitude's beside it, the
/// fixes', and the columns that name theirs; or one bag, its reference's attitude and
/// its `fix_topic` (the attitude's and the fixes' paths then the bag's).
#[derive(Clone, Copy)]
pub struct FixFiles<'a> {
    pub dvl: &'a Path,
    pub attitude: &'a Path,
    pub fixes: &'a Path,
    pub fix_topic: Option<&'a str>,
    pub columns: Option<&'a Path>,
    pub reading: Reading<'a>,
    /// The fixes' latency, s, where given (or carried): each fix read this long before
    /// its stamp.
    pub fix_latency_s: Option<f64>,
}

/// What is read for a fit to fixes: the DVL beside the attitude, the fixes, and the
/// fixes left out, each with its reason.
pub struct FixReading {
    pub read: ReadRecording,
    pub fixes: Fixes,
    pub left_out: Vec<(&'static str, usize)>,
    /// How many fixes read carry no noise of their own (a covariance).
    pub without_noise: usize,
    /// From a bag: the topics and frames read, in words.
    pub read_from: Option<String>,
}

/// What `calibrate --fixes` is asked.
pub struct FixArgs<'a> {
    pub files: FixFiles<'a>,
    pub terms: &'a [TermName],
    pub dive_terms: &'a [TermName],
    /// The fixes' noise per horizontal axis, m, where given (each fix's own, from its
    /// covariance, otherwise), and in depth; the DVL's per axis, cm/s.
    pub fix_noise_m: Option<f64>,
    pub depth_noise_m: Option<f64>,
    /// Whether the fixes' latency is estimated beside the terms.
    pub fix_latency: bool,
    pub dvl_noise_cm_s: f64,
    pub save: Option<&'a Path>,
    /// The folder the corrected recording goes to.
    pub out: &'a Path,
    /// The blackout whose fixes are withheld from the fit, to verify it, where asked.
    pub blackout: Option<BlackoutAsked>,
}

impl FixFiles<'_> {
    /// What fitting the DVL to the fixes will ask of this machine, as `per_row` counts
    /// it.
    pub fn cost(&self, per_row: PerRow) -> Result<Cost, PairedError> {
        Ok(Cost::on(
            per_row,
            vec![self.rows()?],
            machine_memory() as f64,
        ))
    }

    /// The rows of the files read (a bag's messages); refused where the fixes' source
    /// does not match the DVL's (a topic of a CSV file, a file beside a bag).
    pub fn rows(&self) -> Result<Rows, PairedError> {
        match (self.fix_topic, is_bag(self.dvl)) {
            (Some(_), false) => return Err(self.not_a_bag().into()),
            (None, true) => {
                return Err(BagError::Bag {
                    path: self.dvl.to_path_buf(),
                    problem: "--fixes: a bag's fixes are read from its own topic with --fixes-topic, beside its odometry's attitude (--fixes reads CSV files)".into(),
                }
                .into());
            }
            _ => {}
        }
        Rows::count(self.dvl, Some(self.attitude))?.with_fixes(self.fixes, self.fix_topic)
    }

    /// The refusal of fixes from a topic of a recording that is no bag.
    fn not_a_bag(&self) -> BagError {
        BagError::Bag {
            path: self.dvl.to_path_buf(),
            problem: "--fixes-topic: not a bag (a rosbag2 folder, an .mcap or a .db3 file): a CSV recording's fixes are read from --fixes".into(),
        }
    }

    /// Every file read.
    pub fn inputs(&self) -> [Option<&Path>; 4] {
        [
            Some(self.dvl),
            Some(self.attitude),
            Some(self.fixes),
            self.columns,
        ]
    }

    /// Where the fixes come from, as the command line names it.
    pub fn fixes_named(&self) -> String {
        match self.fix_topic {
            Some(topic) => format!("{} --fixes-topic {topic}", self.dvl.display()),
            None => self.fixes.display().to_string(),
        }
    }

    /// The DVL beside the attitude, and the fixes, read and checked ([`Self::read`]),
    /// and the fixes' noise per horizontal axis, m ([`Self::noise_m`]: as `given`, or
    /// the median of their own).
    pub fn read_with_noise(
        &self,
        depth: bool,
        given: Option<f64>,
    ) -> Result<(FixReading, f64), CalibrateError> {
        let mut reading = self.read(depth)?;
        let fix_m = self.noise_m(&mut reading, given)?;
        Ok((reading, fix_m))
    }

    /// The DVL beside the attitude, and the fixes, read and checked: fixes with a depth
    /// where `depth` asks for one, and on the DVL's track ([`same_motion`]).
    fn read(&self, depth: bool) -> Result<FixReading, CalibrateError> {
        let fix_columns = fix_columns(self.columns).map_err(CalibrateError::Columns)?;
        let log = (self.reading.dvl_format).or_else(|| dvl_log::format_of(self.dvl));
        let (read, mut fixes, left_out, (without_noise, read_from)) = match (log, self.fix_topic) {
            (Some(format), _) => self.read_log(format, depth, &fix_columns)?,
            (None, Some(topic)) => self.read_bag(topic, depth)?,
            (None, None) => {
                let columns =
                    columns(self.columns, self.reading).map_err(CalibrateError::Columns)?;
                let read = read_beside_attitude(self.dvl, self.attitude, &columns)?;
                let (fixes, left_out, read_from) = self.fixes_file(&fix_columns)?;
                let without_noise = fixes.len();
                (read, fixes, left_out, (without_noise, read_from))
            }
        };
        for t in &mut fixes.time_s {
            *t -= self.fix_latency_s.unwrap_or(0.0);
        }
        if depth && fixes.depth_m.is_none() {
            return Err(CalibrateError::NoDepths {
                fixes: self.fixes.to_path_buf(),
            });
        }
        same_motion(&self.fixes_named(), &fix_columns, &read.recording, &fixes)?;
        let left_out = left_out.into_iter().filter(|(_, n)| *n > 0).collect();
        Ok(FixReading {
            read,
            fixes,
            left_out,
            without_noise,
            read_from,
        })
    }

    /// The bag's DVL beside its odometry's attitude, and the fixes of its `topic`.
    fn read_bag(&self, topic: &str, depth: bool) -> Result<FixesRead, CalibrateError> {
        let source =
            source(self.dvl, None, self.columns, self.reading).map_err(CalibrateError::Columns)?;
        let Source::Bag { path, topics } = source else {
            return Err(CalibrateError::Read(self.not_a_bag().into()));
        };
        let (read, mut bag) = read_bag_beside_attitude(&path, &topics, topic)?;
        // A fix's altitude (a GNSS's height, a USBL's depth) is fitted only where its
        // noise is given.
        if !depth {
            bag.fixes.depth_m = None;
        }
        let left_out = vec![
            ("no fix (NavSatFix status −1)", bag.no_fix),
            (
                "a latitude and longitude (or x and y) not a number",
                bag.not_a_number,
            ),
        ];
        let read_from = format!(
            "from the bag: {}; of the reference its attitude alone (its velocity not read); the fixes from {} ({})",
            read.frames
                .as_ref()
                .expect("a bag's reading has its frames"),
            bag.topic,
            bag.type_name
        );
        Ok((
            read,
            bag.fixes,
            left_out,
            (bag.without_covariance, Some(read_from)),
        ))
    }

    /// A DVL log beside an attitude and fixes: its own attitude where `--attitude` names
    /// the log again ([`dvl_log::OwnAttitude`]), another file's otherwise (CSV or NMEA);
    /// the GGA sentences its recorder wrote into it where `--fixes` names the log again,
    /// placed on the log's clock, another file's fixes otherwise.
    fn read_log(
        &self,
        format: LogFormat,
        depth: bool,
        fix_columns: &FixColumns,
    ) -> Result<FixesRead, CalibrateError> {
        let thresholds = self.reading.thresholds;
        let (own_attitude, own_fixes) = (
            same_file(self.attitude, self.dvl),
            same_file(self.fixes, self.dvl),
        );
        let (read, log) = if own_attitude {
            read_beside_own_attitude(self.dvl, format, thresholds)?
        } else {
            let columns = columns(self.columns, self.reading).map_err(CalibrateError::Columns)?;
            read_log_beside_attitude((self.dvl, format, thresholds), self.attitude, &columns)?
        };
        let attitude_from = match own_attitude {
            true => format!(
                "of the DVL's own attitude ({})",
                format.own_attitude_words()
            ),
            false => format!("the attitude from {}", self.attitude.display()),
        };
        let head = format!(
            "from the {} log: {}; {attitude_from}",
            format.words(),
            log.summary.frames.join("; ")
        );
        if !own_fixes {
            let (fixes, left_out, from) = self.fixes_file(fix_columns)?;
            let from = from.map_or(head.clone(), |from| format!("{head}; the fixes {from}"));
            let without_noise = fixes.len();
            return Ok((read, fixes, left_out, (without_noise, Some(from))));
        }
        if depth {
            return Err(CalibrateError::NoDepths {
                fixes: self.fixes.to_path_buf(),
            });
        }
        let has_gga = log
            .sentences
            .iter()
            .any(|(_, _, sentence)| is_gga(sentence));
        let logged = fixes_in_log(&log, has_gga);
        let Some((gga, named)) = logged else {
            return Err(CalibrateError::Columns(inputs::refused(
                "--fixes",
                format!(
                    "{}: no fix among the {} {} its recorder wrote into it",
                    self.dvl.display(),
                    match has_gga {
                        true => log.sentences.len(),
                        false => log.navigation.len(),
                    },
                    match has_gga {
                        true => "NMEA sentences (every GGA without a fix, or failing its checksum)",
                        false => "VmDAS navigation blocks and NMEA sentences (no GGA)",
                    }
                ),
            )));
        };
        let from_log = format!(
            "{head}; the fixes from {named}north and east of {:.7}°, {:.7}°), placed on the log's clock, which runs {:.2} s behind the GNSS's (the median of each fix's time less its ping's)",
            gga.origin_deg[0], gga.origin_deg[1], gga.recorder_behind_s
        );
        let (left_out, fixes) = (gga.left_out.clone(), gga.on_the_recorders_clock());
        let without_noise = fixes.len();
        Ok((read, fixes, left_out, (without_noise, Some(from_log))))
    }

    /// The fixes of their own file: an NMEA file's GGA sentences, or a CSV file's
    /// columns; and where they came from, in words, for an NMEA file.
    fn fixes_file(&self, fix_columns: &FixColumns) -> Result<NmeaRead, CalibrateError> {
        if is_nmea(self.fixes) {
            return nmea_fixes(self.fixes);
        }
        let (fixes, _) = read_fixes(self.fixes, fix_columns).map_err(CalibrateError::Fixes)?;
        Ok((fixes, Vec::new(), None))
    }

    /// The fixes' noise per horizontal axis, m: as `given` (the fixes' own then set
    /// aside), or the median of the fixes' own, which each keeps; refused where neither.
    fn noise_m(&self, reading: &mut FixReading, given: Option<f64>) -> Result<f64, CalibrateError> {
        let fixes = &mut reading.fixes;
        if let Some(given) = given {
            fixes.noise_m = None;
            return Ok(given);
        }
        match &fixes.noise_m {
            Some(own) if !own.is_empty() => Ok(crate::median(own)),
            _ => Err(CalibrateError::NoFixNoise {
                flag: match self.fix_topic {
                    Some(topic) => format!("--fixes-topic {topic}"),
                    None => "--fixes".to_string(),
                },
                why: match self.fix_topic {
                    Some(_) => format!(
                        "{} of its {} fixes carry no covariance",
                        reading.without_noise,
                        fixes.len()
                    ),
                    None => "a fixes file gives no noise of its own".to_string(),
                },
            }),
        }
    }
}

/// What `calibrate --fixes` found.
pub struct FixCalibration {
    pub fit: FixFit,
    /// The DVL's samples read, kept and left out, and the fixes read, those left out
    /// with their reasons, and whether each fix was weighed by its own noise (its
    /// covariance; `noise.fix_m` their median) rather than one given.
    pub read: ReadCounts,
    pub fixes: usize,
    pub fixes_left_out: Vec<(&'static str, usize)>,
    /// The fixes' latency given, s: each read this long before its stamp.
    pub fix_latency_s: f64,
    pub own_noise: bool,
    /// From a bag: the topics and frames read, in words.
    pub read_from: Option<String>,
    /// The RMS of the fixes' horizontal residual with no terms (the start positions
    /// alone fitted, to the fixes the fit kept) and with the terms applied, m; and the distance the dead
    /// reckoning travelled over the fixes fitted, m.
    pub before_m: f64,
    pub after_m: f64,
    pub distance_m: f64,
    pub noise: FixNoise,
    /// The fixes the fit was given (a blackout's withheld), which `fit.residuals` index.
    pub fitted_fixes: Fixes,
    /// The DVL's first sample's stamp, s: `--blackout-s` and the figures count from it.
    pub record_start_s: f64,
    /// The dead reckoning scored against the fixes, and across the blackout.
    pub drifts: FixDrifts,
    /// The corrected recording's files written.
    pub corrected: Vec<PathBuf>,
}

/// `calibrate --fixes`: the terms the fixes show, their bound, and the fixes' residual.
pub fn calibrate_fixes(args: &FixArgs) -> Result<FixCalibration, CalibrateError> {
    refused(args)?;
    let files = &args.files;
    let outputs = Outputs::of(args.out, &stem(files.dvl));
    let corrected = [outputs.csv.as_path(), outputs.parquet.as_path()];
    clear_of_inputs(&files.inputs(), &corrected, (args.save, false))?;
    files.cost(FIXES).map_err(CalibrateError::Read)?.state()?;
    let (mut reading, fix_m) = read_dive(args, &outputs)?;
    let record = (&reading.read.recording.time_s[..], &mut reading.fixes);
    let blackout = (args.blackout)
        .map(|asked| withhold(record, asked).map(|(window, fixes)| (asked, window, fixes)))
        .transpose()?;
    let dive = fitted_from(args, (reading, fix_m))?;
    let drifts = dive.drifts(blackout);
    let recording = &dive.reading.read.recording;
    let (fit, sha256) = (&dive.fit, dive.reading.read.dvl_sha256());
    let samples = corrected_samples(&fit.installation, recording, &Reference::new(recording));
    let corrected = write(&outputs, &samples, sha256).map_err(CalibrateError::Write)?;
    if let Some(path) = args.save {
        save(path, args, fit, sha256)?;
    }
    Ok(FixCalibration::of(
        (dive, drifts),
        files.fix_latency_s.unwrap_or(0.0),
        corrected,
    ))
}

impl FixCalibration {
    /// What `dive`'s fit found and its dead reckoning's `drifts`, its fixes read
    /// `fix_latency_s` before their stamps, and the files written of it.
    pub fn of(
        (dive, drifts): (FittedDive, FixDrifts),
        fix_latency_s: f64,
        corrected: Vec<PathBuf>,
    ) -> FixCalibration {
        let FittedDive {
            reading,
            noise,
            fit,
        } = dive;
        let withheld = drifts.blackout.as_ref().map_or(0, |b| b.withheld.len());
        let record_start_s = reading.read.recording.time_s[0];
        FixCalibration {
            corrected,
            read: reading.read.recording.counts().beside_attitude(),
            fixes: reading.fixes.len() + withheld,
            fixes_left_out: reading.left_out,
            fix_latency_s,
            own_noise: reading.fixes.noise_m.is_some(),
            read_from: reading.read_from,
            before_m: horizontal(fit.bare_residual_rms_m),
            after_m: horizontal(fit.residual_rms_m),
            distance_m: fit.distance_m,
            noise,
            fit,
            fitted_fixes: reading.fixes,
            record_start_s,
            drifts,
        }
    }
}

/// One dive read beside its attitude and fixes, and its terms fitted to them.
pub struct FittedDive {
    pub reading: FixReading,
    pub noise: FixNoise,
    pub fit: FixFit,
}

impl FittedDive {
    /// Its dead reckoning scored against its fixes, and across `blackout` where asked.
    pub fn drifts(&self, blackout: Option<(BlackoutAsked, Span, Fixes)>) -> FixDrifts {
        let reading = &self.reading;
        drifts(
            (&reading.read.recording, &reading.fixes, &self.fit),
            blackout,
        )
    }
}

/// The dive of `args` read (refused where `outputs` hold another recording's results)
/// and its terms fitted to its fixes, the fit refused where its residuals contradict
/// the fixes' noise.
pub fn fitted_dive(args: &FixArgs, outputs: &Outputs) -> Result<FittedDive, CalibrateError> {
    fitted_from(args, read_dive(args, outputs)?)
}

/// The dive of `args` read, with the fixes' noise per axis (given, or their own);
/// refused where `outputs` hold another recording's results.
pub fn read_dive(args: &FixArgs, outputs: &Outputs) -> Result<(FixReading, f64), CalibrateError> {
    let files = &args.files;
    let (reading, fix_m) = files.read_with_noise(args.depth_noise_m.is_some(), args.fix_noise_m)?;
    outputs.not_another_recordings(files.dvl, reading.read.dvl_sha256())?;
    Ok((reading, fix_m))
}

/// The terms of `args` fitted to the fixes of the dive `reading`, whose fixes' noise
/// per axis is `fix_m`; refused where the fit's residuals contradict that noise.
pub fn fitted_from(
    args: &FixArgs,
    (reading, fix_m): (FixReading, f64),
) -> Result<FittedDive, CalibrateError> {
    let read = &reading.read;
    let noise = FixNoise {
        fix_m,
        depth_m: args.depth_noise_m.unwrap_or(fix_m),
        dvl_m_s: args.dvl_noise_cm_s / 100.0,
    };
    let terms = FixTerms {
        set: term_set(args.terms),
        fix_latency: args.fix_latency,
    };
    let recording = &read.recording;
    let attitude = Attitude::of(recording);
    let fixes = &reading.fixes;
    let fit = fit_on(recording, &attitude, fixes, terms, noise)
        .map_err(|fault| fix_error(args, fault))?;
    believable(&noise, fixes.rms_noise_m(), &fit)?;
    Ok(FittedDive {
        reading,
        noise,
        fit,
    })
}

/// The shortest step between two fixes whose displacement [`same_motion`] sums, s: long
/// enough that the fixes' noise adds little to the displacement, short enough that a
/// turn takes little from it.
const STEP_S: f64 = 30.0;

/// The least distance, m, the DVL must travel over the fixes' span before
/// [`same_motion`] compares the two.
const LEAST_DISTANCE_M: f64 = 100.0;

/// How many times shorter or longer than the DVL's the fixes' track may be before it is
/// taken as read in another unit: a turn and the fixes' noise move it by well under
/// this; a radian read as a degree, by 57.3.
const UNIT_FACTOR: f64 = 10.0;

/// Refuses fixes whose track over their span is [`UNIT_FACTOR`] times shorter or longer
/// than the DVL's (the median displacement between fixes [`STEP_S`] apart against the
/// median of the DVL's horizontal speed integrated over the same steps): positions in
/// another unit than the columns say (latitude and longitude in radians read as degrees
/// travel 57.3 times less), which no installation explains, before any fit reads them.
/// Medians, so that one fix kilometres off (two steps of a dozen) is the robust fit's to
/// leave out, not taken for another unit.
fn same_motion(
    fixes_named: &str,
    columns: &crate::data::fixes::FixColumns,
    recording: &PairedRecording,
    fixes: &Fixes,
) -> Result<(), CalibrateError> {
    let (time_s, dvl) = (&recording.time_s, &recording.dvl_m_s);
    let (Some(&first), Some(&last)) = (time_s.first(), time_s.last()) else {
        return Ok(());
    };
    let inside: Vec<usize> = (0..fixes.len())
        .filter(|&k| (first..=last).contains(&fixes.time_s[k]))
        .collect();
    // The DVL's horizontal distance up to each sample (no step across a gap), so that a
    // step's is one difference, not a pass over the record.
    let mut travelled_m = vec![0.0; time_s.len()];
    for i in 1..time_s.len() {
        let dt = time_s[i] - time_s[i - 1];
        let step_m = match dt <= recording.gap_limit_s {
            true => dvl[i][0].hypot(dvl[i][1]) * dt,
            false => 0.0,
        };
        travelled_m[i] = travelled_m[i - 1] + step_m;
    }
    // Each step's displacement of the fixes and distance of the DVL, in turn.
    let mut steps: Vec<(f64, f64)> = Vec::new();
    let mut from = inside.first().copied();
    for &k in &inside {
        if let Some(at) = from
            && fixes.time_s[k] - fixes.time_s[at] >= STEP_S
        {
            let [n0, e0] = fixes.north_east_m[at];
            let [n1, e1] = fixes.north_east_m[k];
            // The DVL's samples from the first at or after the step's start to the last
            // at or before its end.
            let low = time_s.partition_point(|&t| t < fixes.time_s[at]);
            let high = time_s.partition_point(|&t| t <= fixes.time_s[k]);
            let dvl_m = match high > low + 1 {
                true => travelled_m[high - 1] - travelled_m[low],
                false => 0.0,
            };
            steps.push(((n1 - n0).hypot(e1 - e0), dvl_m));
            from = Some(k);
        }
    }
    let travelled: f64 = steps.iter().map(|step| step.1).sum();
    if steps.is_empty() || travelled < LEAST_DISTANCE_M {
        return Ok(());
    }
    let median = |values: Vec<f64>| crate::median(&values);
    let fixes_m = median(steps.iter().map(|step| step.0).collect());
    let dvl_m = median(steps.iter().map(|step| step.1).collect());
    let ratio = fixes_m / dvl_m;
    if (1.0 / UNIT_FACTOR..=UNIT_FACTOR).contains(&ratio) {
        return Ok(());
    }
    let radians_as_degrees =
        columns.latitude_longitude.is_some() && columns.angles_in_degrees && ratio < 1.0;
    Err(CalibrateError::FixesOtherMotion {
        fixes: fixes_named.to_string(),
        step_s: STEP_S,
        fixes_m,
        dvl_m,
        hint: match radians_as_degrees {
            true => {
                " (latitude and longitude in radians, read as degrees, travel 57.3 times less: say angles_in_degrees = false in [fix_columns])"
            }
            false => {
                " (positions in another unit than [fix_columns] says, or fixes of another vehicle)"
            }
        },
    })
}

/// Refuses a fit the fixes contradict: residuals [`NOISE_RATIO_LIMIT`] times the noise
/// given or more, or as many times less, by which noise the fit weighs the fixes
/// against the dead reckoning (the dead reckoning's own walk adds to the residuals,
/// well within that factor). Over a quarter of the fixes outliers the fit refuses
/// itself.
fn believable(
    noise: &FixNoise,
    own_rms_m: Option<f64>,
    fit: &FixFit,
) -> Result<(), CalibrateError> {
    // Per horizontal axis, as the noise is given; fixes of their own noise leave its
    // root mean square.
    let read_m = horizontal(fit.residual_rms_m) / std::f64::consts::SQRT_2;
    let ratio = read_m / own_rms_m.unwrap_or(noise.fix_m);
    match ratio < NOISE_RATIO_LIMIT && ratio > 1.0 / NOISE_RATIO_LIMIT {
        true => Ok(()),
        false => Err(CalibrateError::FixNoiseContradicted {
            noise: match own_rms_m {
                Some(rms_m) => format!(
                    "the fixes' own noise (their covariances, RMS {} m)",
                    crate::ThreeFigures(rms_m)
                ),
                None => format!("--fix-noise-m {}", crate::Shown(noise.fix_m)),
            },
            read_m,
            ratio,
        }),
    }
}

/// The fit of `terms` on `recording`'s pieces against `fixes`.
fn fit_on(
    recording: &PairedRecording,
    attitude: &Attitude,
    fixes: &Fixes,
    terms: FixTerms,
    noise: FixNoise,
) -> Result<FixFit, crate::installation::estimate::fixes::FixFitError> {
    let dvl = (&recording.time_s[..], &recording.dvl_m_s[..]);
    fit_fixes(dvl, &recording.pieces(), attitude, fixes, terms, noise)
}

/// The horizontal RMS of per-axis RMS values north and east, m.
fn horizontal(rms_m: crate::Vec3) -> f64 {
    (rms_m[0].powi(2) + rms_m[1].powi(2)).sqrt()
}

/// What a reading for a fit to fixes gives before its common checks: the DVL beside the
/// attitude, the fixes, those left out by reason, how many carry no noise of their own,
/// and what was read there, in words.
type FixesRead = (
    ReadRecording,
    Fixes,
    Vec<(&'static str, usize)>,
    (usize, Option<String>),
);

/// Fixes as an NMEA file gives them: the fixes, those left out by reason, and what was
/// read there, in words.
type NmeaRead = (Fixes, Vec<(&'static str, usize)>, Option<String>);

/// The fixes a DVL log's recorder wrote into it, and where they came from in words:
/// its GGA sentences where it holds any (`has_gga`; VmDAS navigation blocks beside them,
/// then, are not read: said so), its VmDAS navigation blocks otherwise; `None` where
/// they give no fix.
fn fixes_in_log(log: &dvl_log::DvlLog, has_gga: bool) -> Option<(LoggedFixes, String)> {
    match has_gga {
        true => gga_fixes(&log.sentences).map(|gga| {
            let named = format!(
                "its GGA sentences ({} of them without a checksum, so unchecked; {} other sentences passed over{}; ",
                gga.without_checksum,
                gga.others,
                match log.navigation.len() {
                    0 => String::new(),
                    n => format!("; its {n} VmDAS navigation blocks not read"),
                }
            );
            (gga, named)
        }),
        false => navigation_fixes(log).map(|fixes| {
            let named = format!(
                "its VmDAS navigation blocks (each ping's last fix before it; {} blocks repeating the fix before, read once; ",
                fixes.others
            );
            (fixes, named)
        }),
    }
}

/// Whether `a` and `b` name one file (however each is written: `./dvl.pd0`, an
/// absolute path), or, where either cannot be resolved, are the same path.
fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// The GGA fixes of the NMEA file `path` (on UTC, dated by its RMC or ZDA).
fn nmea_fixes(path: &Path) -> Result<NmeaRead, CalibrateError> {
    let (gga, _, undated) = read_nmea_fixes(path)?;
    let mut left_out = gga.left_out.clone();
    left_out.push(("a GGA before any RMC or ZDA gave the date", undated));
    let read_from = format!(
        "from the NMEA file {}: its GGA sentences, each dated by the last RMC or ZDA before it, on UTC in seconds since 1970 (the attitude's clock must be too; north and east of {:.7}°, {:.7}°; {} of them without a checksum, so unchecked)",
        path.display(),
        gga.origin_deg[0],
        gga.origin_deg[1],
        gga.without_checksum
    );
    Ok((gga.fixes, left_out, Some(read_from)))
}

/// Refuses what the fixes cannot fit: a term other than scale, misalignment, lever arm
/// and time offset, a noise that is not a positive number.
pub(crate) fn refused(args: &FixArgs) -> Result<(), CalibrateError> {
    const ALLOWED: [&str; 4] = DEFAULT_FIX_TERMS;
    if let Some(term) = args.terms.iter().find(|t| !ALLOWED.contains(&t.name())) {
        return Err(CalibrateError::Terms(format!(
            "{}: fixes calibrate {} (a bias, or a scale per axis, needs a velocity reference)",
            term.name(),
            ALLOWED.join(", ")
        )));
    }
    // Beyond the Earth's size, no fix's noise.
    let positive = |v: f64| v > 0.0 && v < 1e7;
    if let Some(fix) = args.fix_noise_m.filter(|&f| !positive(f)) {
        return Err(CalibrateError::FixNoise {
            flag: "--fix-noise-m",
            value: fix,
        });
    }
    if let Some(depth) = args.depth_noise_m.filter(|&d| !positive(d)) {
        return Err(CalibrateError::FixNoise {
            flag: "--depth-noise-m",
            value: depth,
        });
    }
    if !positive(args.dvl_noise_cm_s) {
        return Err(CalibrateError::DvlNoise(args.dvl_noise_cm_s));
    }
    if let Some(term) = args.dive_terms.iter().find(|t| t.name() != "time_offset") {
        return Err(CalibrateError::DiveTerms(format!(
            "{}: of the terms fixes calibrate, only time_offset is the dive's",
            term.name()
        )));
    }
    Ok(())
}

/// The fit of `args` failed with `fault`.
fn fix_error(
    args: &FixArgs,
    fault: crate::installation::estimate::fixes::FixFitError,
) -> CalibrateError {
    use crate::installation::estimate::fixes::FixFitError;
    if let FixFitError::Outliers { outliers, within } = fault {
        return CalibrateError::FixOutliers {
            fixes: args.files.fixes_named(),
            outliers,
            within,
        };
    }
    CalibrateError::FixFit {
        fixes: args.files.fixes_named(),
        terms: named(args.terms),
        fault,
    }
}

/// Writes the installation `fit` found to `path`: each term applied with its value and
/// standard deviation; a term not applied (or not estimated) as zero, with the standard
/// deviation the fixes gave it (infinite where they gave none).
fn save(
    path: &Path,
    args: &FixArgs,
    fit: &FixFit,
    recording_sha256: &str,
) -> Result<(), CalibrateError> {
    // The fixes' latency is theirs, not the DVL's installation's: kept apart.
    let dvl_terms = fit.terms.parameter_names().len();
    // Fixes measure no velocity residual: what a dive this installation fits leaves is
    // the DVL's own noise, as given.
    let mut file = SavedInstallation::of(
        &fit.bound.first(dvl_terms),
        (args.terms, args.dive_terms),
        (&args.files.dvl, recording_sha256),
        (args.dvl_noise_cm_s, 0.0),
        [args.dvl_noise_cm_s / 100.0; 3],
    )
    .of_fixes();
    // The fixes' latency, where estimated and applied, beside the installation: the
    // next dive's fixes, of the same system, are read by it.
    if let Some(k) =
        (fit.bound.names.iter()).position(|n| *n == FIX_LATENCY && fit.bound.is_applied(n))
    {
        file = file.with_fix_latency(fit.bound.value[k], fit.bound.std[k]);
    }
    if fit.clock_is_the_sum() {
        file = file.with_time_offset_including_fix_latency();
    }
    file.write(path).map_err(|source| {
        CalibrateError::Write(ResultsError::Io {
            path: path.to_path_buf(),
            source,
        })
    })
}

//! The command line as clap reads it: the subcommands, their arguments and the words
//! they accept. The plotting code's own types name the figure formats and sweep
//! metrics; this module tells clap how they are spelled.

use crate::data::catalogue::Dataset;
use crate::report::compare;
use crate::report::kit::plots::Format;
use crate::report::paper::sweep::Metric;
use clap::builder::PossibleValue;
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};

#[derive(Debug, Parser)]
#[command(
    name = "dcnet-exp",
    version,
    about = "Reproduce and extend the DCNet DVL-calibration experiments"
)]
pub struct Cli {
    /// Worker threads [default: all cores, or RAYON_NUM_THREADS]; results do not depend on it
    #[arg(long, global = true)]
    pub(super) threads: Option<usize>,
    /// Where stderr is not a terminal (a cluster job's log), seconds between two
    /// progress lines of a task [default: 30]
    #[arg(long, global = true, env = "DCNET_LOG_EVERY", value_name = "SECONDS")]
    pub(super) log_every: Option<f64>,
    #[command(subcommand)]
    pub(super) command: Command,
}

#[derive(Debug, Subcommand)]
pub(super) enum Command {
    /// Run an experiment, or every point of its sweep, doing only what is not done yet
    Run(RunArgs),
    /// List every task a run would do, each marked done or to do; changes nothing
    Plan(PlanArgs),
    /// Write the results of a sharded run once every shard has finished
    Collect(CollectArgs),
    /// Draw the figures and write report.md and report.tex from a results folder, re-running nothing
    Plot(PlotArgs),
    /// Compare two results folders (or two sweep points) as Markdown: the spec keys that
    /// differ, every cell with A, B and B − A, differences beyond 2 standard errors marked
    Compare(CompareArgs),
    /// Check a spec (every point of its sweep) and its data files without running anything
    Validate(ValidateArgs),
    /// Calibrate one recording of a DVL beside a reference with attitude: print the
    /// terms with their standard deviations and those the recording cannot show, run
    /// the Kalman filter over it to say how much of the recording its terms needed, and
    /// write the recording corrected (CSV and Parquet)
    Calibrate(CalibrateArgs),
    /// Apply an installation that `calibrate --save` found to another dive: find the
    /// dive's clock again from its first seconds against its reference, write the dive
    /// corrected (CSV and Parquet), and say how well the carried installation fits it
    Correct(CorrectArgs),
    /// Inspect or download the data
    Data {
        #[command(subcommand)]
        command: DataCommand,
    },
    /// Time the dataset generation, the Monte Carlo protocol and DCNet training of a spec
    Bench(BenchArgs),
}

/// The arguments of `run`.
#[derive(Debug, clap::Args)]
pub(super) struct RunArgs {
    #[command(flatten)]
    pub(super) target: Target,
    #[command(flatten)]
    pub(super) drawing: Drawing,
    /// Run only shard K of N (0 ≤ K < N) of the tasks and no results; `--shard N`
    /// takes K from SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX
    #[arg(long, value_name = "K/N")]
    pub(super) shard: Option<String>,
    /// Recompute every task, cached or not
    #[arg(long)]
    pub(super) force: bool,
}

/// The arguments of `plan`.
#[derive(Debug, clap::Args)]
pub(super) struct PlanArgs {
    #[command(flatten)]
    pub(super) target: Target,
    /// List only the tasks of shard K of N
    #[arg(long, value_name = "K/N")]
    pub(super) shard: Option<String>,
}

/// The arguments of `collect`.
#[derive(Debug, clap::Args)]
pub(super) struct CollectArgs {
    #[command(flatten)]
    pub(super) target: Target,
    #[command(flatten)]
    pub(super) drawing: Drawing,
}

/// The arguments of `plot`.
#[derive(Debug, clap::Args)]
pub(super) struct PlotArgs {
    /// A results folder written by `run`, such as results/paper, or a sweep's
    pub(super) results: PathBuf,
    /// Figures go to OUT/<name>/
    #[arg(long, default_value = "plots")]
    pub(super) out: PathBuf,
    /// Write each figure as PNG, SVG or both
    #[arg(long, value_enum, default_value_t = Format::Both)]
    pub(super) format: Format,
    /// What a sweep's figures plot against each swept value
    #[arg(long, value_enum, default_value_t = Metric::EvaluationRmse)]
    pub(super) metric: Metric,
}

/// The arguments of `compare`.
#[derive(Debug, clap::Args)]
pub(super) struct CompareArgs {
    /// The first results folder, such as results/quick or results/<sweep>/<point>
    #[arg(value_name = "A")]
    pub(super) first: PathBuf,
    /// The second results folder
    #[arg(value_name = "B")]
    pub(super) second: PathBuf,
    /// Also write the Markdown to FILE
    #[arg(long, value_name = "FILE", default_value = compare::DEFAULT_FILE)]
    pub(super) out: PathBuf,
}

/// The arguments of `validate`.
#[derive(Debug, clap::Args)]
pub(super) struct ValidateArgs {
    pub(super) spec: PathBuf,
    #[command(flatten)]
    pub(super) overrides: Overrides,
}

/// The arguments of `calibrate`.
#[derive(Debug, clap::Args)]
pub(super) struct CalibrateArgs {
    /// The DVL's CSV file (A-KIT's columns unless --columns names others), a bag, or
    /// the DVL's own log (PD0, Water Linked JSON: beside --reference); several
    /// recordings of the same vehicle are calibrated jointly: the vehicle's terms
    /// shared, each recording's --dive-terms its own
    #[arg(required = true, num_args = 1..)]
    pub(super) dvl: Vec<PathBuf>,
    /// The reference's CSV file, when it is not the DVL's, or an NMEA file (a surface
    /// vehicle's: RMC ground velocity beside PASHR attitude, the down velocity zero);
    /// once per DVL file, in the same order, when there are several
    #[arg(long)]
    pub(super) reference: Vec<PathBuf>,
    /// A TOML file whose [columns] table names the columns (time, dvl, velocity_ned,
    /// attitude, rate, angles_in_degrees, valid, zero_is_valid, gap_limit_s), as an installation spec's
    /// [recordings.columns] does
    #[arg(long)]
    pub(super) columns: Option<PathBuf>,
    #[command(flatten)]
    pub(super) reading: ReadingArgs,
    /// The terms to estimate: scale, scale_per_axis, misalignment, lever_arm,
    /// time_offset, bias, bias_scalar [default: lever_arm,time_offset,bias; with
    /// --fixes: scale,misalignment,lever_arm,time_offset]
    #[arg(long, value_delimiter = ',')]
    pub(super) terms: Option<Vec<String>>,
    #[command(flatten)]
    pub(super) fix: FixFlags,
    /// With --fixes that have a depth: its noise, m [default: --fix-noise-m]
    #[arg(long, value_name = "METRES", allow_negative_numbers = true)]
    pub(super) depth_noise_m: Option<f64>,
    /// With fixes: estimate how late each fix is stamped after the position it gives
    /// (a USBL's acoustic travel and processing), within ±3 s, beside the DVL's clock;
    /// where the two cannot be told apart, their sum is printed
    #[arg(long)]
    pub(super) fix_latency: bool,
    /// Calibrate on the first SECONDS of the recording [default: all of it]
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub(super) window_s: Option<f64>,
    /// The DVL's white noise per axis, cm/s, for the bound
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub(super) dvl_noise_cm_s: f64,
    /// The reference velocity's white noise per axis, cm/s, for the bound [default:
    /// 0.5]
    #[arg(long, allow_negative_numbers = true)]
    pub(super) reference_noise_cm_s: Option<f64>,
    /// How close the Kalman filter's RMSE must stay to its value with the whole
    /// recording, for the length the recording needed: within this % of what
    /// calibration changes (the RMSE before it less that after the fit of all of it)
    /// [default: 10]
    #[arg(long, allow_negative_numbers = true)]
    pub(super) tolerance_pct: Option<f64>,
    /// How far from zero the search for the time offset looks, s: the fit starts from
    /// the search's best (for two logs whose clocks were never set alike) [default:
    /// none, the fit's own scan of ±3 s]
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub(super) search_s: Option<f64>,
    /// Folder the corrected recording and the filter's terms against time go to
    /// [default: calibrated]
    #[arg(long)]
    pub(super) out: Option<PathBuf>,
    /// Save the installation found (terms, standard deviations, correlations) to
    /// this TOML file, for `correct` to apply to other dives
    #[arg(long, value_name = "FILE")]
    pub(super) save: Option<PathBuf>,
    /// Write the calibration's report: report.md, a self-contained report.html and its
    /// figures as PNG and SVG, into --out's folder, or --report=DIR's
    #[arg(long, value_name = "DIR", num_args = 0..=1, require_equals = true)]
    pub(super) report: Option<Option<PathBuf>>,
    /// Hold the calibration to acceptance thresholds, each one's verdict (pass,
    /// marginal, fail) printed and in the report: the misalignment's angle, the
    /// scale's distance from 1, the dead reckoning's end drift; --accept=KEY=VALUE,...
    /// sets them over the defaults misalignment_deg=2,scale_pct=5,drift_pct=0.1
    #[arg(long, value_name = "KEY=VALUE,...", num_args = 0..=1, require_equals = true, default_missing_value = "")]
    pub(super) accept: Option<String>,
    /// With --accept, exit with status 3 where the calibration is rejected (a check
    /// failed or could not be made), after every file is written
    #[arg(long, requires = "accept")]
    pub(super) fail_on_reject: bool,
    /// With --fixes: verify the calibration over a blackout, the fixes inside it
    /// withheld from the fit (the terms printed, saved and applied are that fit's) and
    /// the dead reckoning carried through it, its error at the blackout's end printed
    /// as a share of the distance travelled in it (--accept holds it to drift_pct);
    /// START seconds after the DVL's first stamp, LENGTH seconds long
    #[arg(long, value_name = "START:LENGTH")]
    pub(super) blackout_s: Option<String>,
    /// Which of the terms belong to the dive and are found again on each dive by
    /// `correct` (the rest, the vehicle's, are carried), and with several recordings
    /// are each recording's own: time_offset, bias, bias_scalar
    #[arg(long, value_delimiter = ',', default_value = "time_offset")]
    pub(super) dive_terms: Vec<String>,
}

impl CalibrateArgs {
    /// The reference's noise per axis, cm/s: as given, or 0.5.
    pub(super) fn reference_noise_cm_s(&self) -> f64 {
        self.reference_noise_cm_s.unwrap_or(0.5)
    }

    /// The settling tolerance, %: as given, or 10.
    pub(super) fn tolerance_pct(&self) -> f64 {
        self.tolerance_pct.unwrap_or(10.0)
    }

    /// The folder the corrected recording goes to: as given, or `calibrated`.
    pub(super) fn out(&self) -> &std::path::Path {
        self.out
            .as_deref()
            .unwrap_or(std::path::Path::new("calibrated"))
    }

    /// The folder the report goes to, where one is asked for: as given, or [`Self::out`].
    pub(super) fn report(&self) -> Option<&std::path::Path> {
        (self.report.as_ref()).map(|dir| dir.as_deref().unwrap_or(self.out()))
    }
}

/// Position fixes in place of a velocity reference, for `calibrate` and `correct`.
#[derive(Debug, clap::Args)]
pub(super) struct FixFlags {
    /// Position fixes rather than a velocity reference: a CSV file of a time and a
    /// latitude and longitude (or north and east, m, as its [fix_columns] table in
    /// --columns names them; A-KIT's reference file's by default), optionally a depth,
    /// on the attitude's clock, or an NMEA file of GGA dated by RMC or ZDA (on UTC), or
    /// a DVL log whose recorder wrote GGA into it (named again as --attitude); needs
    /// --attitude and --fix-noise-m; once per DVL file,
    /// in the same order, when there are several (calibrated jointly)
    #[arg(long, value_name = "FILE")]
    pub(super) fixes: Vec<PathBuf>,
    /// With --fixes: the CSV file of the attitude (an AHRS's roll, pitch, yaw, as
    /// [columns] names them), or an NMEA file of PASHR dated by RMC or ZDA (on UTC), on
    /// its own clock and at its own rate; once per --fixes
    #[arg(long, value_name = "FILE")]
    pub(super) attitude: Vec<PathBuf>,
    /// Position fixes from the bag's topic rather than a velocity reference: a
    /// sensor_msgs/msg/NavSatFix, geometry_msgs/msg/PoseWithCovarianceStamped or
    /// nav_msgs/msg/Odometry (its pose), each fix weighed by its covariance; the
    /// attitude from the bag's odometry (--reference-topic), its velocity not read
    #[arg(long, value_name = "TOPIC")]
    pub(super) fixes_topic: Option<String>,
    /// The fixes' noise per horizontal axis, m (a USBL's metres, a GNSS's less);
    /// needed with --fixes, and with --fixes-topic where a fix carries no covariance
    /// (given, it stands for every fix's own)
    #[arg(long, value_name = "METRES", allow_negative_numbers = true)]
    pub(super) fix_noise_m: Option<f64>,
    /// The fixes' latency where it is known (a USBL's specification, a test at the
    /// dock), s: each fix gives the position this long before its stamp, and is read
    /// there
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub(super) fix_latency_s: Option<f64>,
}

/// The longest latency `--fix-latency-s` takes, s: beyond it, fixes are on another
/// clock.
const MAX_FIX_LATENCY_S: f64 = 60.0;

/// Refuses the first of `flags` given (each its name and whether it was), where no
/// position fixes were: each goes with them.
pub(super) fn without_fixes(flags: &[(&str, bool)]) -> Result<(), String> {
    match flags.iter().find(|(_, given)| *given) {
        Some((flag, _)) => Err(format!(
            "{flag}: goes with position fixes: give them with --fixes or --fixes-topic"
        )),
        None => Ok(()),
    }
}

/// `n` files, in words.
fn files(n: usize) -> String {
    match n {
        1 => "1 file".to_string(),
        n => format!("{n} files"),
    }
}

/// Where position fixes come from, as typed.
#[derive(Clone, Copy)]
pub(super) enum GivenFixes<'a> {
    /// A fixes file beside an attitude file.
    Files { fixes: &'a Path, attitude: &'a Path },
    /// A topic of the bag.
    Topic(&'a str),
}

impl FixFlags {
    /// The fixes of one dive, where given, with the attitude they need; the flags given
    /// without fixes refused.
    pub(super) fn given(&self) -> Result<Option<GivenFixes<'_>>, String> {
        Ok(self.given_per_dive(1)?.map(|mut each| each.remove(0)))
    }

    /// The fixes of each of `dives` dives (one recording each), where given, with the
    /// attitude they need; the flags given without fixes refused.
    pub(super) fn given_per_dive(
        &self,
        dives: usize,
    ) -> Result<Option<Vec<GivenFixes<'_>>>, String> {
        if let Some(latency) = self
            .fix_latency_s
            .filter(|l| !(l.abs() <= MAX_FIX_LATENCY_S))
        {
            return Err(format!(
                "--fix-latency-s: {latency} is no latency of a fix: give the seconds each fix is stamped after the position it gives, within ±{MAX_FIX_LATENCY_S} s (beyond, the fixes are on another clock: put them on the attitude's)"
            ));
        }
        match (&self.fixes[..], &self.fixes_topic) {
            ([_, ..], Some(_)) => Err(
                "--fixes-topic: fixes come from a file (--fixes) or from a bag's topic (--fixes-topic): give one"
                    .into(),
            ),
            ([], Some(topic)) => match &self.attitude[..] {
                [_, ..] => Err(
                    "--attitude: with --fixes-topic the attitude is the bag's own (its odometry, --reference-topic)"
                        .into(),
                ),
                [] => Ok(Some(vec![GivenFixes::Topic(topic); dives])),
            },
            (fixes @ [_, ..], None) if fixes.len() != dives => Err(format!(
                "--fixes: {} for {}: give one --fixes per DVL file, in the same order",
                files(fixes.len()),
                files(dives).replace("file", "DVL file")
            )),
            (fixes @ [_, ..], None) => match self.attitude.len() {
                0 => Err(
                    "--fixes: give the attitude beside it with --attitude (an AHRS's roll, pitch and yaw)"
                        .into(),
                ),
                n if n != fixes.len() => Err(format!(
                    "--attitude: {} for {} --fixes: give one --attitude per --fixes, in the same order",
                    files(n),
                    fixes.len()
                )),
                _ => Ok(Some(
                    (fixes.iter().zip(&self.attitude))
                        .map(|(fixes, attitude)| GivenFixes::Files { fixes, attitude })
                        .collect(),
                )),
            },
            ([], None) => {
                without_fixes(&[
                    ("--attitude", !self.attitude.is_empty()),
                    ("--fix-noise-m", self.fix_noise_m.is_some()),
                    ("--fix-latency-s", self.fix_latency_s.is_some()),
                ])?;
                Ok(None)
            }
        }
    }
}

/// How `calibrate` and `correct` read a recording beyond its columns.
#[derive(Debug, clap::Args)]
pub(super) struct ReadingArgs {
    /// The DVL's validity column, where it has one: 1 or true for a valid sample, 0 or
    /// false for one it did not measure (left out and counted); as `valid` in the
    /// --columns table
    #[arg(long, value_name = "NAME")]
    pub(super) valid_column: Option<String>,
    /// The longest step between two of the DVL's valid samples, s, that does not cut
    /// the recording into pieces (the filter's and the noise's correlation in time are
    /// not read across a longer one) [default: three of the DVL's sample intervals]; as
    /// `gap_limit_s` in the --columns table
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub(super) gap_limit_s: Option<f64>,
    /// A bag's DVL topic [default: its only DVL topic]: marine_acoustic_msgs/msg/Dvl,
    /// geometry_msgs/msg/TwistWithCovarianceStamped or TwistStamped
    #[arg(long, value_name = "TOPIC")]
    pub(super) dvl_topic: Option<String>,
    /// A bag's reference topic [default: its only nav_msgs/msg/Odometry topic]
    #[arg(long, value_name = "TOPIC")]
    pub(super) reference_topic: Option<String>,
    /// A bag's sensor_msgs/msg/Imu topic for the body rate [default: the reference's
    /// twist, or the attitude's change where it carries none]
    #[arg(long, value_name = "TOPIC")]
    pub(super) rate_topic: Option<String>,
    /// A bag's stamps: the headers' (when each measurement was valid) or the
    /// recording's (when the bag received it)
    /// [default: header]
    #[arg(long, value_enum)]
    pub(super) stamps: Option<StampsArg>,
    /// A bag's body frame: the reference's twist is in it, the DVL's frame is placed in
    /// it by /tf_static, and the installation is reported in it (forward-left-up, as
    /// REP-103 has it, unless its name ends in _frd)
    /// [default: base_link]
    #[arg(long, value_name = "FRAME")]
    pub(super) frame: Option<String>,
    /// The DVL file's format where it is the DVL's own log [default: found from its
    /// content: PD0 by its 0x7F 0x7F, Water Linked's by a JSON object with a "type"];
    /// its reference is then the CSV file --reference
    #[arg(long, value_enum)]
    pub(super) dvl_format: Option<DvlFormatArg>,
    /// A DVL log's bottom-track correlation a beam must reach to count, 0–255
    /// [default: the instrument's own verdict]
    #[arg(long, value_name = "COUNTS")]
    pub(super) bt_correlation_min: Option<u8>,
    /// A DVL log's bottom-track percent good a beam must reach to count, in beam
    /// coordinates, % [default: the instrument's own verdict]
    #[arg(long, value_name = "PERCENT")]
    pub(super) bt_percent_good_min: Option<u8>,
}

/// A DVL log's format, as typed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum DvlFormatArg {
    /// Teledyne RDI's binary PD0
    Pd0,
    /// Water Linked's JSON reports (A50, A125), one a line
    WaterLinked,
}

/// The stamps a bag is read on, as typed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum StampsArg {
    Header,
    Receive,
}

impl DvlFormatArg {
    /// The format as the library names it.
    pub(super) fn format(self) -> crate::data::paired::dvl_log::LogFormat {
        match self {
            DvlFormatArg::Pd0 => crate::data::paired::dvl_log::LogFormat::Pd0,
            DvlFormatArg::WaterLinked => crate::data::paired::dvl_log::LogFormat::WaterLinked,
        }
    }
}

impl ReadingArgs {
    /// As the operator's commands take it.
    pub(super) fn reading(&self) -> crate::operator::inputs::Reading<'_> {
        crate::operator::inputs::Reading {
            valid_column: self.valid_column.as_deref(),
            gap_limit_s: self.gap_limit_s,
            dvl_topic: self.dvl_topic.as_deref(),
            reference_topic: self.reference_topic.as_deref(),
            rate_topic: self.rate_topic.as_deref(),
            stamps: self.stamps.map(|stamps| match stamps {
                StampsArg::Header => crate::data::paired::bag::Stamps::Header,
                StampsArg::Receive => crate::data::paired::bag::Stamps::Receive,
            }),
            frame: self.frame.as_deref(),
            dvl_format: self.dvl_format.map(DvlFormatArg::format),
            thresholds: crate::data::paired::dvl_log::Thresholds {
                correlation_min: self.bt_correlation_min,
                percent_good_min: self.bt_percent_good_min,
            },
        }
    }
}

/// The arguments of `correct`.
#[derive(Debug, clap::Args)]
pub(super) struct CorrectArgs {
    /// The dive's DVL CSV file, bag, or DVL log (PD0, Water Linked JSON)
    pub(super) dvl: PathBuf,
    /// The installation file `calibrate --save` wrote
    #[arg(long, value_name = "FILE")]
    pub(super) installation: PathBuf,
    /// The reference's CSV file, when it is not the DVL's, or an NMEA file as for
    /// calibrate (its body rate corrects the lever arm; its velocity finds the clock)
    #[arg(long)]
    pub(super) reference: Option<PathBuf>,
    /// A TOML file whose [columns] table names the columns, as for calibrate
    #[arg(long)]
    pub(super) columns: Option<PathBuf>,
    #[command(flatten)]
    pub(super) reading: ReadingArgs,
    #[command(flatten)]
    pub(super) fix: FixFlags,
    /// The first SECONDS of the dive that find its clock again; scored after them
    /// [default: 60; with --fixes, the whole dive's fixes]
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub(super) window_s: Option<f64>,
    /// How far from the calibration's time offset the search for the clock looks, s
    /// [default: 30; with --fixes, the fit's own scan of ±3 s]
    #[arg(long, allow_negative_numbers = true)]
    pub(super) search_s: Option<f64>,
    /// The dive's time offset, s, where it is known: no search
    #[arg(long, allow_negative_numbers = true)]
    pub(super) time_offset_s: Option<f64>,
    /// Folder the corrected dive goes to
    #[arg(long, default_value = "corrected")]
    pub(super) out: PathBuf,
    /// Write the correction's report: report.md, a self-contained report.html and its
    /// figures (the clock search, the residual, the track where the reference records
    /// positions) as PNG and SVG, into --out's folder, or --report=DIR's
    #[arg(long, value_name = "DIR", num_args = 0..=1, require_equals = true)]
    pub(super) report: Option<Option<PathBuf>>,
    /// Hold the installation carried to this dive to an acceptance threshold, its
    /// verdict (pass, marginal, fail) printed and in the report: the dead reckoning's
    /// end drift on the dive against the reference's positions or the fixes, which its
    /// calibration did not see; --accept=drift_pct=VALUE sets it over the default 0.1
    #[arg(long, value_name = "drift_pct=VALUE", num_args = 0..=1, require_equals = true, default_missing_value = "")]
    pub(super) accept: Option<String>,
    /// With --accept, exit with status 3 where the installation is rejected on this
    /// dive (its drift failed or could not be scored), after every file is written
    #[arg(long, requires = "accept")]
    pub(super) fail_on_reject: bool,
}

/// The arguments of `bench`.
#[derive(Debug, clap::Args)]
pub(super) struct BenchArgs {
    pub(super) spec: PathBuf,
    /// Timed repetitions of each stage (training: paired runs, ours then the peer's)
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub(super) repeat: u32,
    /// Training batches timed per model
    #[arg(long, default_value_t = 40, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub(super) training_batches: u32,
    /// The PyTorch peer script (torch_dcnet.py): times the same network in PyTorch
    /// in the same arrangements, side by side
    #[arg(long, value_name = "SCRIPT")]
    pub(super) pytorch: Option<PathBuf>,
    /// Times training on 1, 2, 4, … cores up to all of them (--threads), in each
    /// arrangement, rather than on all of them only
    #[arg(long)]
    pub(super) scaling: bool,
    #[command(flatten)]
    pub(super) overrides: Overrides,
}

/// The spec a command works on and where its results go.
#[derive(Debug, clap::Args)]
pub(super) struct Target {
    pub(super) spec: PathBuf,
    /// Results go to OUT/<name>/, the cache to OUT/.cache/
    #[arg(long, default_value = "results")]
    pub(super) out: PathBuf,
    /// burn CPU backend for DCNet, overriding training.backend: flex or ndarray
    #[arg(long)]
    pub(super) backend: Option<String>,
    #[command(flatten)]
    pub(super) overrides: Overrides,
}

impl Target {
    /// The command line of `verb` on this target, with its `--out`, `--backend` and
    /// `--set` as given, for a message that tells a user what to run next.
    pub(super) fn command(&self, verb: &str) -> String {
        let quoted = |text: &str| {
            if text
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_./=,:".contains(c))
            {
                text.to_string()
            } else {
                format!("'{}'", text.replace('\'', r"'\''"))
            }
        };
        let mut line = format!("dcnet-exp {verb} {}", quoted(&self.spec.to_string_lossy()));
        if self.out != Path::new("results") {
            line.push_str(&format!(" --out {}", quoted(&self.out.to_string_lossy())));
        }
        if let Some(backend) = &self.backend {
            line.push_str(&format!(" --backend {}", quoted(backend)));
        }
        for set in &self.overrides.set {
            line.push_str(&format!(" --set {}", quoted(set)));
        }
        line
    }
}

/// Where the figures of the results a command writes go.
#[derive(Debug, clap::Args)]
pub(super) struct Drawing {
    /// Figures go to PLOTS/<name>/
    #[arg(long, default_value = "plots")]
    pub(super) plots: PathBuf,
    /// Write the results and the reports but draw no figures
    #[arg(long)]
    pub(super) no_plots: bool,
}

impl Drawing {
    pub(super) fn folder(&self) -> Option<&Path> {
        (!self.no_plots).then_some(self.plots.as_path())
    }
}

#[derive(Debug, Subcommand)]
pub(super) enum DataCommand {
    /// Trajectories, lengths, mean speeds, window counts and dataset size of a spec;
    /// or a ROS 2 bag's topics: types, message counts, rates, time span, and which
    /// this tool reads; or a DVL's own log (PD0, Water Linked JSON): its span, pings
    /// kept and left out by reason, frames and data types
    Info {
        spec: PathBuf,
        #[command(flatten)]
        overrides: Overrides,
        /// The file's format where it is a DVL's own log [default: found from its
        /// content]
        #[arg(long, value_enum)]
        dvl_format: Option<DvlFormatArg>,
    },
    /// Download a dataset's recordings and check their SHA-256: `data fetch` (or `data fetch
    /// snapir`) the Snapir recordings, `data fetch akit` the A-KIT recordings
    Fetch {
        /// Which recordings
        #[arg(value_enum, default_value_t = Dataset::Snapir)]
        dataset: Dataset,
        /// Folder to write the files to [default: data/snapir, or data/akit for akit]
        #[arg(long)]
        dest: Option<PathBuf>,
        /// Where the files are served [default: the BeamsNet repository, or the A-KIT
        /// repository's Data/ folder at the checked commit for akit]
        #[arg(long)]
        base_url: Option<String>,
    },
}

#[derive(Debug, clap::Args)]
pub(super) struct Overrides {
    /// Override a spec key, e.g. --set calibration.monte_carlo_runs=50 (value read as TOML)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub(super) set: Vec<String>,
}

impl clap::ValueEnum for Format {
    fn value_variants<'a>() -> &'a [Self] {
        &Format::ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.name()))
    }
}

impl clap::ValueEnum for Metric {
    fn value_variants<'a>() -> &'a [Self] {
        &Metric::ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.name()).help(self.description()))
    }
}

impl clap::ValueEnum for Dataset {
    fn value_variants<'a>() -> &'a [Self] {
        &Dataset::ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.name()).help(self.description()))
    }
}

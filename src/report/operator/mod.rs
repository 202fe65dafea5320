//! The room of the operator's commands: what `calibrate` and `correct` print about
//! the recordings given on the command line, with the kit's readable terms. In: a
//! calibration of one recording or of several jointly ([`calibrate`]), or a recording's
//! clock found again and its correction ([`correct`]). Out: the text printed on stdout.
//! They draw no figures: their results are the files `results::corrected` writes.

pub mod calibrate;
pub mod correct;

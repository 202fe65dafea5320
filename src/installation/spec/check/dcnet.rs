//! Checks `[dcnet]`. In: the paper spec whose trained DCNet models the study applies,
//! relative to the spec's folder, and whether `calibration.methods` lists "dcnet".
//! Out: the paper spec's path when "dcnet" is listed; the table is needed then and
//! left unread otherwise.

use crate::installation::spec::file::DcnetModelsFile;
use crate::spec::check::Faults;
use std::path::{Path, PathBuf};

/// Checks `[dcnet]` against `wants_dcnet`; its spec found from `folder`.
pub(in crate::installation::spec) fn check_dcnet(
    dcnet: Option<DcnetModelsFile>,
    wants_dcnet: bool,
    folder: &Path,
    faults: &mut Faults,
) -> Option<PathBuf> {
    match (dcnet, wants_dcnet) {
        (Some(DcnetModelsFile { spec }), true) => Some(folder.join(spec)),
        (None, true) => {
            faults.add("dcnet", "is missing: the method \"dcnet\" needs [dcnet] spec = \"<paper spec>\", whose trained models it applies");
            None
        }
        (_, false) => None,
    }
}

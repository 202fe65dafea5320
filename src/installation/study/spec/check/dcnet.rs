//! Checks `[dcnet]`. In: the paper spec whose trained DCNet models the study applies,
//! relative to the spec's folder, and whether `calibration.methods` lists "dcnet".
//! Out: the paper spec's path when "dcnet" is listed; the table is needed then and
//! left unread otherwise.

use crate::installation::study::spec::file::DcnetModelsFile;
use crate::spec::check::Faults;
use std::path::{Path, PathBuf};

/// Checks `[dcnet]` against `wants_dcnet`; its spec found from `folder`.
pub(in crate::installation::study::spec) fn check_dcnet(
    dcnet: Option<DcnetModelsFile>,
    wants_dcnet: bool,
    folder: &Path,
    faults: &mut Faults,
) -> Option<PathBuf> {
    match (dcnet, wants_dcnet) {
        (Some(DcnetModelsFile { spec }), true) => {
            let path = folder.join(spec);
            // A study's spec has no models: the paper spec is the one without a kind.
            if let Ok(Some(kind)) = crate::spec::declared_kind(&path) {
                faults.add(
                    "dcnet.spec",
                    format!(
                        "{} is a spec of kind {kind:?}: [dcnet] names the paper spec whose trained DCNet models the study applies",
                        path.display()
                    ),
                );
            }
            Some(path)
        }
        (None, true) => {
            faults.add("dcnet", "is missing: the method \"dcnet\" needs [dcnet] spec = \"<paper spec>\", whose trained models it applies");
            None
        }
        (_, false) => None,
    }
}

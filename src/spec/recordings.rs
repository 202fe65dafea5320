//! The Snapir recordings a spec can name (`V.npy`, `V_test.npy`): their names, where
//! they are published, the SHA-256 each must have, and the hint that a missing one's
//! error gives. `dcnet-exp data fetch` downloads them from this list.

use std::path::Path;

/// One file to download: its name in the destination folder, its path under the base
/// URL, its size in bytes and the SHA-256 it must have.
#[derive(Debug, Clone, Copy)]
pub struct RemoteFile {
    pub name: &'static str,
    pub remote_path: &'static str,
    pub size_bytes: u64,
    pub sha256: &'static str,
}

/// The Snapir recordings.
pub const FILES: [RemoteFile; 2] = [
    RemoteFile {
        name: "V.npy",
        remote_path: "dataset/TrainAndValidation/V.npy",
        size_bytes: 333_392,
        sha256: "0c525b3f30e71f0d385af5c256930b0fc8bb9cc2e53581cda46943bb49308ed5",
    },
    RemoteFile {
        name: "V_test.npy",
        remote_path: "dataset/Test/V_test.npy",
        size_bytes: 48_152,
        sha256: "ee517105d2a2856d5c5ee062c979d7a11e2fe929ae776bb341c8bf1ebe1014f7",
    },
];

/// A hint to append to a "file not found" message when the file is one we can fetch.
pub fn hint_for(path: &Path) -> String {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or_default();
    if FILES.iter().any(|file| file.name == name) {
        let folder = path
            .parent()
            .map(|p| p.display().to_string())
            .unwrap_or_default();
        format!(
            "; run `dcnet-exp data fetch --dest {folder}` to download the Snapir recordings there"
        )
    } else {
        String::new()
    }
}

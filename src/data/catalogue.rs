//! The recordings `dcnet-exp data fetch` can download, and where from: the Snapir
//! recordings (`V.npy`, `V_test.npy`, listed in [`crate::spec::recordings`], which a
//! spec's check needs below this module) from the BeamsNet repository, and the 13
//! A-KIT segments (a DVL beside an INS reference, two CSV files each) from the A-KIT
//! repository at a fixed commit: each [`Dataset`]'s URL, destination folder, file
//! names, sizes and SHA-256s, and the hint a missing A-KIT file's error gives. In:
//! nothing (constants). Out: the lists `data fetch` downloads and the A-KIT files a
//! paired recording names.

use crate::spec::recordings::{FILES, RemoteFile};
use std::path::Path;

/// Raw files of the BeamsNet repository (Cohen & Klein 2022) on its main branch.
pub const DEFAULT_BASE_URL: &str = "https://raw.githubusercontent.com/ansfl/BeamsNet/main";

/// Where `dcnet-exp data fetch` puts the files, relative to the working directory.
pub const DEFAULT_DEST: &str = "data/snapir";

/// Raw files of the A-KIT repository (Cohen & Klein 2025), folder `Data/`, at the
/// commit whose files [`AKIT_FILES`] lists.
pub const AKIT_BASE_URL: &str =
    "https://raw.githubusercontent.com/ansfl/A-KIT/0c4fca0c00727a0bf9a343d2af3101200ac9aeaa/Data";

/// Where `dcnet-exp data fetch akit` puts the files, relative to the working directory.
pub const AKIT_DEST: &str = "data/akit";

/// How many segments the A-KIT recordings have: `Trajectory1/` to `Trajectory13/`.
pub const AKIT_SEGMENTS: usize = 13;

/// A set of recordings `dcnet-exp data fetch` can download.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dataset {
    /// `V.npy` and `V_test.npy`, the DCNet paper's data.
    Snapir,
    /// The 13 A-KIT segments: the DVL and the INS reference of each.
    Akit,
}

impl Dataset {
    pub const ALL: [Dataset; 2] = [Dataset::Snapir, Dataset::Akit];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Dataset::Snapir => "snapir",
            Dataset::Akit => "akit",
        }
    }

    /// What it is, for `--help`.
    pub fn description(self) -> &'static str {
        match self {
            Dataset::Snapir => {
                "the Snapir recordings V.npy and V_test.npy (BeamsNet), to data/snapir/"
            }
            Dataset::Akit => {
                "the A-KIT recordings: DVL and INS reference, 13 segments (A-KIT), to data/akit/"
            }
        }
    }

    /// Its files, with their paths below the base URL and their hashes.
    pub fn files(self) -> &'static [RemoteFile] {
        match self {
            Dataset::Snapir => &FILES,
            Dataset::Akit => &AKIT_FILES,
        }
    }

    /// Where its files are served unless `--base-url` says otherwise.
    pub fn default_base_url(self) -> &'static str {
        match self {
            Dataset::Snapir => DEFAULT_BASE_URL,
            Dataset::Akit => AKIT_BASE_URL,
        }
    }

    /// Where its files go unless `--dest` says otherwise.
    pub fn default_dest(self) -> &'static str {
        match self {
            Dataset::Snapir => DEFAULT_DEST,
            Dataset::Akit => AKIT_DEST,
        }
    }
}

/// The A-KIT recordings, by their paths below the repository's `Data/` folder, which
/// are also their places below the destination folder: per segment N,
/// `TrajectoryN/DVL_trajectoryN.csv` and `TrajectoryN/GT_trajectoryN.csv`.
pub const AKIT_FILES: [RemoteFile; 2 * AKIT_SEGMENTS] = [
    RemoteFile {
        name: "Trajectory1/DVL_trajectory1.csv",
        remote_path: "Trajectory1/DVL_trajectory1.csv",
        size_bytes: 31_931,
        sha256: "cd66e7d147b636b2d8af44456440fb4eb5cf685a739e2032d0fbe114b9c3fa80",
    },
    RemoteFile {
        name: "Trajectory1/GT_trajectory1.csv",
        remote_path: "Trajectory1/GT_trajectory1.csv",
        size_bytes: 63_496,
        sha256: "8f144085883417533abfc4f4b3a56a4ca241e074be9a6e307e3eb80266c7e292",
    },
    RemoteFile {
        name: "Trajectory2/DVL_trajectory2.csv",
        remote_path: "Trajectory2/DVL_trajectory2.csv",
        size_bytes: 31_927,
        sha256: "afb9ce0ff5d7e083884b5d6d1ced3a0acc42e50fb74cfaa14a45e9b6285393a7",
    },
    RemoteFile {
        name: "Trajectory2/GT_trajectory2.csv",
        remote_path: "Trajectory2/GT_trajectory2.csv",
        size_bytes: 63_291,
        sha256: "ef11449482548e5b94ef85523baa0031a24c590678516b322efaf7ef2851e006",
    },
    RemoteFile {
        name: "Trajectory3/DVL_trajectory3.csv",
        remote_path: "Trajectory3/DVL_trajectory3.csv",
        size_bytes: 31_939,
        sha256: "d346d171a2d9051ba80278816fab49107a022099a7226ea279d05cee3e02c193",
    },
    RemoteFile {
        name: "Trajectory3/GT_trajectory3.csv",
        remote_path: "Trajectory3/GT_trajectory3.csv",
        size_bytes: 63_287,
        sha256: "41fd557e23f35db25dc24175e142e5c5216e7e87833f93dd7e456b531f9af179",
    },
    RemoteFile {
        name: "Trajectory4/DVL_trajectory4.csv",
        remote_path: "Trajectory4/DVL_trajectory4.csv",
        size_bytes: 31_738,
        sha256: "30de3956e98dba1324df1e542003c3cf24ebb93812bb4a5118c8e5d19fc70e32",
    },
    RemoteFile {
        name: "Trajectory4/GT_trajectory4.csv",
        remote_path: "Trajectory4/GT_trajectory4.csv",
        size_bytes: 63_171,
        sha256: "6f3693dc986e995f535cd936ee6108808a9767f4d1699fdf5e9c37290f95bc1c",
    },
    RemoteFile {
        name: "Trajectory5/DVL_trajectory5.csv",
        remote_path: "Trajectory5/DVL_trajectory5.csv",
        size_bytes: 31_815,
        sha256: "b59a57d0d7eb58bace6726dcbe6b8233e0bd518507884553953127872d8f3925",
    },
    RemoteFile {
        name: "Trajectory5/GT_trajectory5.csv",
        remote_path: "Trajectory5/GT_trajectory5.csv",
        size_bytes: 63_399,
        sha256: "684abbc18c279264f5fce73e50f232f67987d04e93798adc4fd01faacfb07e95",
    },
    RemoteFile {
        name: "Trajectory6/DVL_trajectory6.csv",
        remote_path: "Trajectory6/DVL_trajectory6.csv",
        size_bytes: 31_960,
        sha256: "f7c7bb5974ded6995f7af9cc73aa7ae1136e3deca09da6bdac772a364677a64c",
    },
    RemoteFile {
        name: "Trajectory6/GT_trajectory6.csv",
        remote_path: "Trajectory6/GT_trajectory6.csv",
        size_bytes: 63_567,
        sha256: "fe633c7876c63bd4ea9855d4ee0c875a292c488b1de7d0555b26c26a464aa4ab",
    },
    RemoteFile {
        name: "Trajectory7/DVL_trajectory7.csv",
        remote_path: "Trajectory7/DVL_trajectory7.csv",
        size_bytes: 31_723,
        sha256: "8e7c348ccb2e7e61336b7e0f2b06dfb2fc632dc6c4b4ebaf3c806de21dbd2da7",
    },
    RemoteFile {
        name: "Trajectory7/GT_trajectory7.csv",
        remote_path: "Trajectory7/GT_trajectory7.csv",
        size_bytes: 63_270,
        sha256: "ef5515e88b938298949e63aa85094a1e9d162b26ec7944c2bb8119d4bad80247",
    },
    RemoteFile {
        name: "Trajectory8/DVL_trajectory8.csv",
        remote_path: "Trajectory8/DVL_trajectory8.csv",
        size_bytes: 31_802,
        sha256: "984a155335f44f60b19b9becb41180ac2046000d68b35333bf5db5c15873db78",
    },
    RemoteFile {
        name: "Trajectory8/GT_trajectory8.csv",
        remote_path: "Trajectory8/GT_trajectory8.csv",
        size_bytes: 63_399,
        sha256: "b3c31b4ad8bfd8f67e62ba0a22c93cca8da62fe3b5c92027620478b0229e3156",
    },
    RemoteFile {
        name: "Trajectory9/DVL_trajectory9.csv",
        remote_path: "Trajectory9/DVL_trajectory9.csv",
        size_bytes: 31_395,
        sha256: "a739f677843d6d3eea0a6c63ff2220cef34c499003da3b15dee6a4b389323d21",
    },
    RemoteFile {
        name: "Trajectory9/GT_trajectory9.csv",
        remote_path: "Trajectory9/GT_trajectory9.csv",
        size_bytes: 62_984,
        sha256: "af31ec490641d55e9d572f03de686315d02f25f249c49f4e8ad372907f624557",
    },
    RemoteFile {
        name: "Trajectory10/DVL_trajectory10.csv",
        remote_path: "Trajectory10/DVL_trajectory10.csv",
        size_bytes: 31_780,
        sha256: "72ef5665ae12b0d5ae0381d359d4888e81a398f3011f7017a4fe9ed8523c06dc",
    },
    RemoteFile {
        name: "Trajectory10/GT_trajectory10.csv",
        remote_path: "Trajectory10/GT_trajectory10.csv",
        size_bytes: 63_403,
        sha256: "7e65f8275baf516df49ad217457a61528cf1faab7341840907764efb45f2af73",
    },
    RemoteFile {
        name: "Trajectory11/DVL_trajectory11.csv",
        remote_path: "Trajectory11/DVL_trajectory11.csv",
        size_bytes: 31_878,
        sha256: "aa7e1e94070ea50a5db6a50bf850f3b1b2279d7cc43587181b0d9456a19fd17d",
    },
    RemoteFile {
        name: "Trajectory11/GT_trajectory11.csv",
        remote_path: "Trajectory11/GT_trajectory11.csv",
        size_bytes: 63_372,
        sha256: "67547347c892af3b85bdc8bba4683fdebe6ae2e57c234429067ebf78a55a264a",
    },
    RemoteFile {
        name: "Trajectory12/DVL_trajectory12.csv",
        remote_path: "Trajectory12/DVL_trajectory12.csv",
        size_bytes: 32_006,
        sha256: "a3bddd7b41f5509cbe8a41c7403d09fbd8a9343089e0f04c6ec87834c985ac41",
    },
    RemoteFile {
        name: "Trajectory12/GT_trajectory12.csv",
        remote_path: "Trajectory12/GT_trajectory12.csv",
        size_bytes: 63_455,
        sha256: "e06bb93a3e55ba34e7b8fff0321cef1698bcaa14453323a52d03afb330382842",
    },
    RemoteFile {
        name: "Trajectory13/DVL_trajectory13.csv",
        remote_path: "Trajectory13/DVL_trajectory13.csv",
        size_bytes: 31_899,
        sha256: "5a6c3958bd95da0dc4717fb2db2a11caf7ee1ef0030fe5d252b85e0268988613",
    },
    RemoteFile {
        name: "Trajectory13/GT_trajectory13.csv",
        remote_path: "Trajectory13/GT_trajectory13.csv",
        size_bytes: 63_257,
        sha256: "5d035f6fc11632dc0ea82d6b20599b147abcef3379daee332d058c57e3a7c95f",
    },
];

/// A hint to append to a "file not found" message when the file is one of the A-KIT
/// recordings: the command that downloads them where it was looked for.
pub fn akit_hint(path: &Path) -> String {
    let name = AKIT_FILES
        .iter()
        .map(|file| Path::new(file.name))
        .find(|name| path.ends_with(name));
    match name {
        Some(name) => {
            let folder = path
                .ancestors()
                .nth(name.components().count())
                .map(|p| p.display().to_string())
                .filter(|p| !p.is_empty())
                .unwrap_or_else(|| ".".into());
            format!(
                "; run `dcnet-exp data fetch akit --dest {folder}` to download the A-KIT recordings there"
            )
        }
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_dataset_lists_its_files_once_with_their_sizes_and_hashes() {
        assert_eq!(Dataset::Snapir.files().len(), 2);
        assert_eq!(Dataset::Akit.files().len(), 26);
        for dataset in Dataset::ALL {
            let names: std::collections::BTreeSet<_> =
                dataset.files().iter().map(|file| file.name).collect();
            assert_eq!(names.len(), dataset.files().len(), "{dataset:?}");
            for file in dataset.files() {
                assert_eq!(file.sha256.len(), 64, "{}", file.name);
                assert!(file.sha256.bytes().all(|b| b.is_ascii_hexdigit()));
                assert!(file.size_bytes > 0);
            }
        }
        assert_eq!(AKIT_FILES[25].name, "Trajectory13/GT_trajectory13.csv");
        assert_eq!(AKIT_FILES[25].size_bytes, 63_257);
        assert_eq!(
            AKIT_FILES[25].sha256,
            "5d035f6fc11632dc0ea82d6b20599b147abcef3379daee332d058c57e3a7c95f"
        );
    }

    #[test]
    fn a_missing_akit_file_is_given_the_command_that_fetches_it() {
        assert_eq!(
            akit_hint(Path::new("/data/akit/Trajectory7/GT_trajectory7.csv")),
            "; run `dcnet-exp data fetch akit --dest /data/akit` to download the A-KIT recordings there"
        );
        assert_eq!(
            akit_hint(Path::new("Trajectory7/GT_trajectory7.csv")),
            "; run `dcnet-exp data fetch akit --dest .` to download the A-KIT recordings there"
        );
        assert_eq!(akit_hint(Path::new("/data/akit/GT_trajectory7.csv")), "");
        assert_eq!(akit_hint(Path::new("/data/V.npy")), "");
    }
}

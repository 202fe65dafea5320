//! A rosbag2 bag on disk: a folder (`metadata.yaml` beside its files, split files in
//! its order) or one `.mcap` or `.db3` file. [`Bag::stream`] reads each file once,
//! front to back, hashing it as it goes, and hands the messages of the topics asked for
//! to the caller; every other message is counted and dropped at once, so a bag that
//! also holds a camera is read in the memory of the topics asked for. A damaged or
//! truncated MCAP file is refused at the byte where its reading stopped.
//! In: a bag's path. Out: its [`Topic`]s with their message counts and spans, their
//! [`Definitions`], and the SHA-256 of each file.

use super::BagError;
use super::definitions::{Definitions, full_name};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Whether a topic's messages are read, by its name, its type and the definitions read
/// so far.
pub type Wanted = dyn Fn(&str, &str, &Definitions) -> bool;

/// What is done with a message read: given its topic (whose count is the message's
/// place in it), the definitions and its recording time, ns.
pub type Visit<'a> = dyn FnMut(&Topic, &Definitions, u64, &[u8]) -> Result<(), BagError> + 'a;

/// How a bag's messages are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Storage {
    Mcap,
    Sqlite,
}

/// A bag: where it is, its files in order, and how they store their messages.
#[derive(Debug, Clone)]
pub struct Bag {
    pub path: PathBuf,
    pub files: Vec<PathBuf>,
    pub storage: Storage,
}

/// One topic of a bag: its name, its type, and its messages' count and span of
/// recording times, ns.
#[derive(Debug, Clone, PartialEq)]
pub struct Topic {
    pub name: String,
    pub type_name: String,
    pub count: u64,
    pub first_ns: Option<u64>,
    pub last_ns: Option<u64>,
}

impl Topic {
    /// Its messages per second over its span (none with fewer than two).
    pub fn rate_hz(&self) -> Option<f64> {
        match (self.first_ns, self.last_ns) {
            (Some(first), Some(last)) if last > first && self.count > 1 => {
                Some((self.count - 1) as f64 / ((last - first) as f64 * 1e-9))
            }
            _ => None,
        }
    }
}

/// What a pass over a bag found: its topics in the order first seen, the definitions
/// of their types, and each file with its SHA-256.
#[derive(Debug, Clone, Default)]
pub struct Survey {
    pub topics: Vec<Topic>,
    pub definitions: Definitions,
    pub sha256: Vec<(PathBuf, String)>,
}

impl Survey {
    fn topic(&mut self, name: &str, type_name: &str) -> usize {
        match self.topics.iter().position(|t| t.name == name) {
            Some(at) => at,
            None => {
                self.topics.push(Topic {
                    name: name.to_string(),
                    type_name: full_name(type_name),
                    count: 0,
                    first_ns: None,
                    last_ns: None,
                });
                self.topics.len() - 1
            }
        }
    }

    fn count(&mut self, at: usize, time_ns: u64) {
        let topic = &mut self.topics[at];
        topic.count += 1;
        topic.first_ns = Some(topic.first_ns.map_or(time_ns, |t| t.min(time_ns)));
        topic.last_ns = Some(topic.last_ns.map_or(time_ns, |t| t.max(time_ns)));
    }
}

/// Whether `path` is a bag: a folder with `metadata.yaml`, or a `.mcap` or `.db3` file.
pub fn is_bag(path: &Path) -> bool {
    if path.is_dir() {
        return path.join("metadata.yaml").is_file();
    }
    matches!(
        path.extension().and_then(|e| e.to_str()),
        Some("mcap" | "db3")
    )
}

impl Bag {
    /// The bag at `path`.
    pub fn open(path: &Path) -> Result<Bag, BagError> {
        let at = |problem: String| BagError::Bag {
            path: path.to_path_buf(),
            problem,
        };
        if !path.exists() {
            return Err(at("not found".into()));
        }
        if path.is_dir() {
            return Self::folder(path).map_err(at);
        }
        let storage = match path.extension().and_then(|e| e.to_str()) {
            Some("mcap") => Storage::Mcap,
            Some("db3") => Storage::Sqlite,
            _ => {
                return Err(at(
                    "not a bag: a bag is a rosbag2 folder, an .mcap or a .db3 file".into(),
                ));
            }
        };
        Ok(Bag {
            path: path.to_path_buf(),
            files: vec![path.to_path_buf()],
            storage,
        })
    }

    /// A rosbag2 folder: its files as `metadata.yaml` lists them.
    fn folder(path: &Path) -> Result<Bag, String> {
        #[derive(serde::Deserialize)]
        struct Metadata {
            rosbag2_bagfile_information: Information,
        }
        #[derive(serde::Deserialize)]
        struct Information {
            storage_identifier: String,
            relative_file_paths: Vec<PathBuf>,
            #[serde(default)]
            compression_format: String,
        }
        let metadata = path.join("metadata.yaml");
        let text = std::fs::read_to_string(&metadata).map_err(|e| {
            format!(
                "{}: {e} (a rosbag2 folder holds metadata.yaml)",
                metadata.display()
            )
        })?;
        let information = serde_yaml_ng::from_str::<Metadata>(&text)
            .map_err(|e| format!("{}: {e}", metadata.display()))?
            .rosbag2_bagfile_information;
        if !information.compression_format.is_empty() {
            return Err(format!(
                "{}: compression_format {:?}: a bag compressed by rosbag2 is not read here; decompress it first (`ros2 bag decompress`), or record with MCAP's own chunk compression",
                metadata.display(),
                information.compression_format
            ));
        }
        let storage = match information.storage_identifier.as_str() {
            "mcap" => Storage::Mcap,
            "sqlite3" => Storage::Sqlite,
            other => {
                return Err(format!(
                    "{}: storage_identifier {other:?}: this tool reads mcap and sqlite3",
                    metadata.display()
                ));
            }
        };
        let files: Vec<PathBuf> = (information.relative_file_paths.iter())
            .map(|f| path.join(f))
            .collect();
        if files.is_empty() {
            return Err(format!(
                "{}: relative_file_paths lists no file",
                metadata.display()
            ));
        }
        if let Some(missing) = files.iter().find(|f| !f.is_file()) {
            return Err(format!(
                "{} is listed in metadata.yaml but not there",
                missing.display()
            ));
        }
        Ok(Bag {
            path: path.to_path_buf(),
            files,
            storage,
        })
    }

    /// Reads every file once, front to back: each message of a topic `wanted` takes
    /// (by its name, its type and the definitions read so far) goes to `visit` with its
    /// topic (whose count is the message's place among its topic's, 1 for the first),
    /// the definitions and its recording time, ns; every message is counted.
    pub fn stream(&self, wanted: &Wanted, visit: &mut Visit) -> Result<Survey, BagError> {
        let mut survey = Survey::default();
        for file in &self.files {
            let sha256 = match self.storage {
                Storage::Mcap => stream_mcap(file, &mut survey, wanted, visit)?,
                Storage::Sqlite => stream_sqlite(file, &mut survey, wanted, visit)?,
            };
            survey.sha256.push((file.clone(), sha256));
        }
        Ok(survey)
    }

    /// Its topics with their message counts (no spans) and their types' definitions,
    /// from an MCAP file's summary section or a sqlite3 file's index, without reading
    /// its messages where it can.
    pub fn counts(&self) -> Result<Survey, BagError> {
        let mut survey = Survey::default();
        for file in &self.files {
            let found = match self.storage {
                Storage::Mcap => mcap_summary(file, &mut survey)?,
                Storage::Sqlite => sqlite_counts(file, &mut survey)?,
            };
            if !found {
                return self.survey();
            }
        }
        Ok(survey)
    }

    /// Its topics, counted, with their types' definitions: a pass that keeps no
    /// message.
    pub fn survey(&self) -> Result<Survey, BagError> {
        self.stream(&|_, _, _| false, &mut |_, _, _, _| Ok(()))
    }
}

/// One MCAP file streamed; its SHA-256.
fn stream_mcap(
    path: &Path,
    survey: &mut Survey,
    wanted: &Wanted,
    visit: &mut Visit,
) -> Result<String, BagError> {
    use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut hasher = Sha256::new();
    let mut fed: u64 = 0;
    let damaged = |fed: u64, problem: String| BagError::Damaged {
        path: path.to_path_buf(),
        byte: fed,
        problem,
    };
    let mut channels = Channels::default();
    // No record longer than the file (a damaged length is refused, not allocated), and
    // every chunk's CRC checked (a flipped bit is refused, not read).
    let size = file.metadata().map_err(io)?.len();
    let options = LinearReaderOptions::default()
        .with_record_length_limit(usize::try_from(size).unwrap_or(usize::MAX))
        .with_validate_chunk_crcs(true);
    let mut reader = LinearReader::new_with_options(options);
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| damaged(fed, e.to_string()))? {
            LinearReadEvent::ReadRequest(need) => {
                let buffer = reader.insert(need);
                let read = loop {
                    match file.read(buffer) {
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        other => break other.map_err(io)?,
                    }
                };
                hasher.update(&buffer[..read]);
                fed += read as u64;
                reader.notify_read(read);
            }
            LinearReadEvent::Record { data, opcode } => {
                let record =
                    mcap::parse_record(opcode, data).map_err(|e| damaged(fed, e.to_string()))?;
                channels.take(record, survey, (wanted, visit), &|problem| {
                    damaged(fed, problem)
                })?;
            }
        }
    }
    Ok(format!("{:x}", hasher.finalize()))
}

/// An MCAP file's schemas' names and channels as read so far: each channel's topic's
/// place in the survey, and whether its messages are wanted.
#[derive(Default)]
struct Channels {
    schemas: BTreeMap<u16, String>,
    channels: BTreeMap<u16, (usize, bool)>,
}

impl Channels {
    /// Takes one record: a schema's definitions and a channel are kept, a message
    /// counted (and visited where its topic is wanted); a fault is `damaged`'s.
    fn take(
        &mut self,
        record: mcap::records::Record,
        survey: &mut Survey,
        (wanted, visit): (&Wanted, &mut Visit),
        damaged: &dyn Fn(String) -> BagError,
    ) -> Result<(), BagError> {
        use mcap::records::Record;
        match record {
            Record::Schema { header, data } => {
                if header.encoding == "ros2msg" {
                    let text = String::from_utf8_lossy(&data);
                    (survey.definitions.add(&header.name, &text))
                        .map_err(|e| damaged(format!("schema {}: {e}", header.name)))?;
                }
                self.schemas.insert(header.id, header.name);
            }
            Record::Channel(channel) => {
                let type_name = (self.schemas.get(&channel.schema_id))
                    .cloned()
                    .unwrap_or_default();
                let at = survey.topic(&channel.topic, &type_name);
                let readable = channel.message_encoding == "cdr"
                    && wanted(
                        &channel.topic,
                        &survey.topics[at].type_name,
                        &survey.definitions,
                    );
                self.channels.insert(channel.id, (at, readable));
            }
            Record::Message { header, data } => {
                let Some(&(at, readable)) = self.channels.get(&header.channel_id) else {
                    return Err(damaged(format!(
                        "a message on channel {} that no channel record precedes",
                        header.channel_id
                    )));
                };
                survey.count(at, header.log_time);
                if readable {
                    visit(
                        &survey.topics[at],
                        &survey.definitions,
                        header.log_time,
                        &data,
                    )?;
                }
            }
            _ => {}
        }
        Ok(())
    }
}

/// A sqlite3 error of the bag at `path`, as the bag's fault.
fn sqlite_fault(path: &Path) -> impl Fn(rusqlite::Error) -> BagError + '_ {
    move |e| BagError::Bag {
        path: path.to_path_buf(),
        problem: format!("not a readable sqlite3 bag: {e}"),
    }
}

/// The sqlite3 file at `path` opened to read, its types read by the definitions this
/// tool carries (added to `survey`'s).
fn open_sqlite(path: &Path, survey: &mut Survey) -> Result<rusqlite::Connection, BagError> {
    use rusqlite::{Connection, OpenFlags};
    if survey.definitions.types.is_empty() {
        survey.definitions = Definitions::carried();
    }
    Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY).map_err(sqlite_fault(path))
}

/// One sqlite3 file streamed in the order of its messages' recording times; its
/// SHA-256. Its types are read by the definitions this tool carries.
fn stream_sqlite(
    path: &Path,
    survey: &mut Survey,
    wanted: &Wanted,
    visit: &mut Visit,
) -> Result<String, BagError> {
    let fault = sqlite_fault(path);
    let connection = open_sqlite(path, survey)?;
    let mut topics: BTreeMap<i64, (usize, bool)> = BTreeMap::new();
    {
        let mut statement = (connection
            .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id"))
        .map_err(&fault)?;
        let mut rows = statement.query([]).map_err(&fault)?;
        while let Some(row) = rows.next().map_err(&fault)? {
            let (id, name, type_name, format): (i64, String, String, String) = (
                row.get(0).map_err(&fault)?,
                row.get(1).map_err(&fault)?,
                row.get(2).map_err(&fault)?,
                row.get(3).map_err(&fault)?,
            );
            let at = survey.topic(&name, &type_name);
            let readable =
                format == "cdr" && wanted(&name, &survey.topics[at].type_name, &survey.definitions);
            topics.insert(id, (at, readable));
        }
    }
    let mut statement = (connection
        .prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id"))
    .map_err(&fault)?;
    let mut rows = statement.query([]).map_err(&fault)?;
    while let Some(row) = rows.next().map_err(&fault)? {
        let id: i64 = row.get(0).map_err(&fault)?;
        let time_ns: i64 = row.get(1).map_err(&fault)?;
        let Some(&(at, readable)) = topics.get(&id) else {
            return Err(BagError::Bag {
                path: path.to_path_buf(),
                problem: format!(
                    "a message of topic id {id}, which the topics table does not list"
                ),
            });
        };
        let Ok(time_ns) = u64::try_from(time_ns) else {
            return Err(BagError::Message {
                path: path.to_path_buf(),
                topic: survey.topics[at].name.clone(),
                message: survey.topics[at].count + 1,
                problem: format!(
                    "its receive stamp is {time_ns} ns, before 1970: a bag's stamps count from the epoch, and this one is not read as 0 or any other"
                ),
            });
        };
        survey.count(at, time_ns);
        if readable {
            let data = row
                .get_ref(2)
                .map_err(&fault)?
                .as_blob()
                .map_err(|e| fault(e.into()))?;
            visit(&survey.topics[at], &survey.definitions, time_ns, data)?;
        }
    }
    file_sha256(path).map_err(|source| BagError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The SHA-256 of the file at `path`, read a MiB at a time.
fn file_sha256(path: &Path) -> std::io::Result<String> {
    let mut file = std::fs::File::open(path)?;
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 20];
    loop {
        match file.read(&mut buffer) {
            Ok(0) => return Ok(format!("{:x}", hasher.finalize())),
            Ok(read) => hasher.update(&buffer[..read]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
}

/// Adds the topics and counts of an MCAP file's summary to `survey`; false where the
/// file has no summary with statistics (a bag cut short, or written without one).
fn mcap_summary(path: &Path, survey: &mut Survey) -> Result<bool, BagError> {
    use mcap::sans_io::summary_reader::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
    use std::io::Seek;
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    let mut reader =
        SummaryReader::new_with_options(SummaryReaderOptions::default().with_file_size(size));
    while let Some(event) = reader.next_event() {
        let Ok(event) = event else {
            return Ok(false);
        };
        match event {
            SummaryReadEvent::ReadRequest(need) => {
                let read = file.read(reader.insert(need)).map_err(io)?;
                reader.notify_read(read);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let at = file.seek(to).map_err(io)?;
                reader.notify_seeked(at);
            }
        }
    }
    let Some(summary) = reader.finish() else {
        return Ok(false);
    };
    let Some(stats) = &summary.stats else {
        return Ok(false);
    };
    let mut channels: Vec<_> = summary.channels.values().collect();
    channels.sort_by_key(|c| c.id);
    for channel in channels {
        let type_name = channel
            .schema
            .as_ref()
            .map(|s| s.name.clone())
            .unwrap_or_default();
        if let Some(schema) = &channel.schema
            && schema.encoding == "ros2msg"
        {
            let text = String::from_utf8_lossy(&schema.data);
            survey
                .definitions
                .add(&schema.name, &text)
                .map_err(|e| BagError::Bag {
                    path: path.to_path_buf(),
                    problem: format!("schema {}: {e}", schema.name),
                })?;
        }
        let at = survey.topic(&channel.topic, &type_name);
        survey.topics[at].count += stats
            .channel_message_counts
            .get(&channel.id)
            .copied()
            .unwrap_or(0);
    }
    Ok(true)
}

/// Adds the topics and counts of a sqlite3 file to `survey`.
fn sqlite_counts(path: &Path, survey: &mut Survey) -> Result<bool, BagError> {
    let fault = sqlite_fault(path);
    let connection = open_sqlite(path, survey)?;
    let mut statement = (connection.prepare(
        "SELECT t.name, t.type, COUNT(m.id) FROM topics t LEFT JOIN messages m ON m.topic_id = t.id GROUP BY t.id ORDER BY t.id",
    ))
    .map_err(&fault)?;
    let mut rows = statement.query([]).map_err(&fault)?;
    while let Some(row) = rows.next().map_err(&fault)? {
        let (name, type_name, count): (String, String, i64) = (
            row.get(0).map_err(&fault)?,
            row.get(1).map_err(&fault)?,
            row.get(2).map_err(&fault)?,
        );
        let at = survey.topic(&name, &type_name);
        survey.topics[at].count += count.max(0) as u64;
    }
    Ok(true)
}

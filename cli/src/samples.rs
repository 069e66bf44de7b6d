//! Reading `{"samples": [...]}` input with messages that name the sample and the field.
//!
//! The text is deserialized straight into the numbers the command needs (no `serde_json::Value` tree,
//! which costs about 70 bytes per byte of text): every sample's requested fields are written into one
//! flat `Vec<f64>`, everything else is skipped without being stored, and a vector longer than the model
//! needs is refused as soon as its first extra entry is read. Memory is therefore 8 bytes per accepted
//! number. A field that is missing, short or holds a non-number is recorded and reported when the
//! command reaches that sample; the samples after it are only checked to be valid JSON (the command
//! cannot succeed any more, and storing them could cost more than their text), so invalid JSON anywhere
//! is still reported as such.
//!
//! A command may also read optional fields (absent: `None`, not an error) and external wrenches, `"f_ext":
//! {"LINK": {"force": [3], "torque": [3]}, …}` (CONTRACT §2), each link looked up among the model's frames
//! as its key is read and each wrench stored as 6 numbers and the frame's index: memory stays a few bytes
//! per byte of text, and a link given twice in one sample is refused (a JSON object's repeated key would
//! otherwise silently replace the first wrench; two wrenches on a link are added up by the caller).

use super::{CliError, InputError, InternalError, SampleProblem, WrenchPartProblem};
use serde::de::{self, DeserializeSeed, IgnoredAny, MapAccess, SeqAccess, Visitor};
use std::collections::HashMap;
use std::fmt;

/// The visitor methods of every JSON scalar (`bool`, numbers, strings, `null`), each running `$body` with
/// the visitor bound to `$this`: a value of the wrong kind is recorded, not an error of the parse.
macro_rules! forward_scalars {
    (|mut $this:ident| $body:block) => {
        forward_scalars!(@each (mut $this) $body);
    };
    (|$this:ident| $body:block) => {
        forward_scalars!(@each ($this) $body);
    };
    (@each ($($binding:tt)+) $body:block) => {
        fn visit_bool<E: de::Error>(self, _: bool) -> Result<Self::Value, E> {
            let $($binding)+ = self;
            $body
        }
        fn visit_i64<E: de::Error>(self, _: i64) -> Result<Self::Value, E> {
            let $($binding)+ = self;
            $body
        }
        fn visit_u64<E: de::Error>(self, _: u64) -> Result<Self::Value, E> {
            let $($binding)+ = self;
            $body
        }
        fn visit_f64<E: de::Error>(self, _: f64) -> Result<Self::Value, E> {
            let $($binding)+ = self;
            $body
        }
        fn visit_str<E: de::Error>(self, _: &str) -> Result<Self::Value, E> {
            let $($binding)+ = self;
            $body
        }
        fn visit_unit<E: de::Error>(self) -> Result<Self::Value, E> {
            let $($binding)+ = self;
            $body
        }
    };
}

/// The fields a command reads from every sample: names and the lengths the model needs.
pub type Request = [(&'static str, usize)];

/// The name of the external wrenches' field.
pub const F_EXT: &str = "f_ext";

/// What a command reads besides the required fields of its [`Request`].
#[derive(Default)]
pub struct Extras<'a> {
    /// Fields of the request that a sample may leave out ([`Samples::optional_vector`]).
    pub optional: &'a [&'static str],
    /// The model's frames (link names, in frame order) when the samples may carry `f_ext`.
    pub links: Option<&'a [&'a str]>,
}

/// One external wrench of a sample: the frame's index in the list given to [`Samples::parse_with`],
/// force and torque in the link's frame, about its origin (CONTRACT §2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wrench {
    /// Index of the link among the frames given.
    pub frame: usize,
    /// Force (N).
    pub force: [f64; 3],
    /// Torque (N·m).
    pub torque: [f64; 3],
}

/// The samples of an input: `len()` samples, each with the requested fields.
pub struct Samples {
    request: Vec<(&'static str, usize)>,
    /// Whether each requested field may be absent.
    optional: Vec<bool>,
    /// For every sample and requested field (sample after sample): an optional field that is absent.
    absent: Vec<bool>,
    /// Whether `f_ext` is read (its problems are recorded as field index `request.len()`).
    reads_wrenches: bool,
    /// Where each sample's wrenches start in `wrenches`.
    wrench_starts: Vec<usize>,
    /// All samples' wrenches, sample after sample.
    wrenches: Vec<Wrench>,
    /// Where each requested field starts within a sample's numbers.
    offsets: Vec<usize>,
    /// The sum of the requested lengths: each sample's share of `numbers`.
    stride: usize,
    count: usize,
    /// All samples' requested fields, sample after sample, field after field in request order (a field
    /// with a problem keeps zeros in its place).
    numbers: Vec<f64>,
    /// The fields of the last sample that cannot be used: `(sample, field index, what is wrong)`. Only
    /// the first sample with a problem is kept (see the module documentation).
    problems: Vec<(usize, usize, Problem)>,
}

/// What is wrong with a requested field of one sample (reported when the sample is used).
#[derive(Debug, Clone)]
enum Problem {
    Missing,
    NotArray,
    /// Fewer entries than the model needs (how many).
    Short(usize),
    /// The right length, but entry `index` is not a finite number (shown as JSON).
    NotFinite {
        index: usize,
        shown: String,
    },
    /// `f_ext` is not an object.
    NotWrenches,
    /// `f_ext` names a link the model does not have (its name and the model's links with a close name).
    UnknownLink {
        link: String,
        suggestions: Vec<String>,
    },
    /// `f_ext` names a link twice.
    DuplicateLink(String),
    /// A link's wrench is not an object.
    WrenchNotObject(String),
    /// A link's `force` or `torque`.
    WrenchPart {
        link: String,
        part: &'static str,
        problem: WrenchPartProblem,
    },
}

impl Problem {
    /// The problem as the command reports it (`len`: the entries the field needs).
    fn reported(&self, len: usize) -> SampleProblem {
        match self {
            Problem::Missing => SampleProblem::Missing,
            Problem::NotArray => SampleProblem::NotArray,
            Problem::Short(got) => SampleProblem::Length {
                got: *got,
                expected: len,
            },
            Problem::NotFinite { index, shown } => SampleProblem::NotFinite {
                index: *index,
                shown: shown.clone(),
            },
            Problem::NotWrenches => SampleProblem::NotWrenches,
            Problem::UnknownLink { link, suggestions } => SampleProblem::UnknownLink {
                link: link.clone(),
                suggestions: suggestions.clone(),
            },
            Problem::DuplicateLink(link) => SampleProblem::DuplicateLink { link: link.clone() },
            Problem::WrenchNotObject(link) => SampleProblem::WrenchNotObject { link: link.clone() },
            Problem::WrenchPart {
                link,
                part,
                problem,
            } => SampleProblem::WrenchPart {
                link: link.clone(),
                part,
                problem: problem.clone(),
            },
        }
    }
}

impl Samples {
    /// Reads `text`, keeping the fields of `request` of every sample.
    pub fn parse(text: &str, request: &Request) -> Result<Self, CliError> {
        Self::parse_with(text, request, &Extras::default())
    }

    /// [`Samples::parse`], with optional fields and external wrenches as `extras` says.
    pub fn parse_with(text: &str, request: &Request, extras: &Extras) -> Result<Self, CliError> {
        let offsets = request
            .iter()
            .scan(0, |at, &(_, len)| {
                let start = *at;
                *at += len;
                Some(start)
            })
            .collect();
        let mut reader = Reader {
            samples: Samples {
                request: request.to_vec(),
                offsets,
                stride: request.iter().map(|&(_, len)| len).sum(),
                count: 0,
                numbers: Vec::new(),
                problems: Vec::new(),
                optional: request
                    .iter()
                    .map(|(name, _)| extras.optional.contains(name))
                    .collect(),
                absent: Vec::new(),
                reads_wrenches: extras.links.is_some(),
                wrench_starts: Vec::new(),
                wrenches: Vec::new(),
            },
            root: Root::NoSamples,
            stopped: false,
            refusal: None,
            links: extras.links.map(|names| LinkTable {
                index: names
                    .iter()
                    .enumerate()
                    .map(|(k, &n)| (n.to_string(), k))
                    .collect(),
                names: names.iter().map(|n| n.to_string()).collect(),
                stamps: vec![0; names.len()],
                stamp: 0,
            }),
        };
        let mut deserializer = serde_json::Deserializer::from_str(text);
        let parsed = RootSeed(&mut reader)
            .deserialize(&mut deserializer)
            .and_then(|()| deserializer.end());
        if let Err(e) = parsed {
            // A refusal made while reading is the error itself; serde_json's is about the text.
            return Err(CliError::Input(match reader.refusal.take() {
                Some(refusal) => refusal,
                None => InputError::NotJson(e),
            }));
        }
        match reader.root {
            Root::NoSamples => Err(InputError::NoSamples.into()),
            Root::NotArray => Err(InputError::SamplesNotArray.into()),
            Root::Array => Ok(reader.samples),
        }
    }

    /// How many samples the input holds.
    pub fn len(&self) -> usize {
        self.count
    }

    /// The first problem of any sample, in sample and field order: `--engine generated` checks the
    /// whole input before it compiles anything, so a wrong length is reported at once.
    pub fn check_all(&self) -> Result<(), CliError> {
        for index in 0..self.count {
            for &(name, _) in &self.request {
                self.optional_vector(index, name)?;
            }
            if self.reads_wrenches {
                self.wrenches(index)?;
            }
        }
        Ok(())
    }

    /// Field `name` of sample `index` as [`Samples::vector`] gives it, `None` if it is an optional field
    /// the sample leaves out.
    pub fn optional_vector(&self, index: usize, name: &str) -> Result<Option<&[f64]>, CliError> {
        let stride = self.request.len();
        let field = self.request.iter().position(|&(n, _)| n == name);
        match field {
            Some(f) if self.optional[f] && self.absent.get(index * stride + f) == Some(&true) => {
                Ok(None)
            }
            _ => self.vector(index, name).map(Some),
        }
    }

    /// Whether any sample carries at least one external wrench.
    pub fn has_wrenches(&self) -> bool {
        !self.wrenches.is_empty()
    }

    /// The external wrenches of sample `index` (none if it has no `f_ext`).
    pub fn wrenches(&self, index: usize) -> Result<&[Wrench], CliError> {
        if !self.reads_wrenches {
            return Err(InternalError::FieldNotRead {
                field: F_EXT.to_string(),
            }
            .into());
        }
        let field = self.request.len();
        let problem = self
            .problems
            .iter()
            .find(|&&(s, f, _)| (s, f) == (index, field));
        if let Some((_, _, problem)) = problem {
            return Err(CliError::Sample {
                sample: index,
                field: F_EXT.to_string(),
                problem: problem.reported(0),
            });
        }
        let (Some(&start), end) = (
            self.wrench_starts.get(index),
            self.wrench_starts
                .get(index + 1)
                .copied()
                .unwrap_or(self.wrenches.len()),
        ) else {
            return Err(InternalError::SampleNotInInput { sample: index }.into());
        };
        Ok(&self.wrenches[start..end])
    }

    /// Field `name` (one of the request) of sample `index` as exactly the requested number of finite
    /// numbers.
    pub fn vector(&self, index: usize, name: &str) -> Result<&[f64], CliError> {
        let Some(field) = self.request.iter().position(|&(n, _)| n == name) else {
            return Err(InternalError::FieldNotRead {
                field: name.to_string(),
            }
            .into());
        };
        let len = self.request[field].1;
        let problem = self
            .problems
            .iter()
            .find(|&&(s, f, _)| (s, f) == (index, field));
        if let Some((_, _, problem)) = problem {
            return Err(CliError::Sample {
                sample: index,
                field: name.to_string(),
                problem: problem.reported(len),
            });
        }
        let start = index * self.stride + self.offsets[field];
        self.numbers
            .get(start..start + len)
            .ok_or_else(|| InternalError::SampleNotInInput { sample: index }.into())
    }
}

/// What the document's field `samples` turned out to be (the last one counts, as for any JSON object
/// read into a map).
enum Root {
    NoSamples,
    NotArray,
    Array,
}

/// The state of one read: the samples so far, and the message of a refusal made while reading.
struct Reader {
    samples: Samples,
    root: Root,
    /// A sample with a problem has been read: the rest is skipped.
    stopped: bool,
    refusal: Option<InputError>,
    /// The model's links, when `f_ext` is read.
    links: Option<LinkTable>,
}

/// The model's links by name, and which of them the `f_ext` being read has named.
struct LinkTable {
    index: HashMap<String, usize>,
    names: Vec<String>,
    /// `stamps[k] == stamp`: link `k` is named in the current `f_ext` object.
    stamps: Vec<u64>,
    stamp: u64,
}

impl Reader {
    /// Stops the read with `refusal` as the command's error.
    fn refuse<E: de::Error>(&mut self, refusal: InputError) -> E {
        let error = E::custom(&refusal);
        self.refusal = Some(refusal);
        error
    }
}

/// The document: an object whose field `samples` is read; anything else is not a samples document.
struct RootSeed<'a>(&'a mut Reader);

impl<'de> DeserializeSeed<'de> for RootSeed<'_> {
    type Value = ();
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for RootSeed<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON document")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        while let Some(key) = map.next_key_seed(NameSeed(&["samples"]))? {
            match key {
                Some(_) => map.next_value_seed(SamplesSeed(&mut *self.0))?,
                None => map.next_value::<IgnoredAny>().map(drop)?,
            }
        }
        Ok(())
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<(), A::Error> {
        skip_seq(seq)
    }
    forward_scalars!(|_self| { Ok(()) });
}

/// The array `samples`: each element read into the flat numbers.
struct SamplesSeed<'a>(&'a mut Reader);

impl<'de> DeserializeSeed<'de> for SamplesSeed<'_> {
    type Value = ();
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        // A repeated `samples` replaces the earlier one.
        let samples = &mut self.0.samples;
        samples.count = 0;
        samples.numbers.clear();
        samples.problems.clear();
        samples.absent.clear();
        samples.wrench_starts.clear();
        samples.wrenches.clear();
        self.0.stopped = false;
        self.0.root = Root::NotArray;
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for SamplesSeed<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("the samples")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        self.0.root = Root::Array;
        while !self.0.stopped {
            if seq.next_element_seed(SampleSeed(&mut *self.0))?.is_none() {
                return Ok(());
            }
        }
        skip_seq(seq)
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<(), A::Error> {
        skip_map(map)
    }
    forward_scalars!(|_self| { Ok(()) });
}

/// One sample: an object whose requested fields are read; a sample that is not an object has none.
struct SampleSeed<'a>(&'a mut Reader);

impl SampleSeed<'_> {
    /// Makes room for the sample's numbers, returning its index.
    fn begin(&mut self) -> usize {
        let samples = &mut self.0.samples;
        let index = samples.count;
        samples.count += 1;
        let end = samples.numbers.len() + samples.stride;
        samples.numbers.resize(end, 0.0);
        let end = samples.absent.len() + samples.request.len();
        samples.absent.resize(end, false);
        samples.wrench_starts.push(samples.wrenches.len());
        index
    }

    /// Records every requested field not in `seen` as missing; after a sample with a problem the read
    /// stops keeping samples.
    fn end(&mut self, index: usize, seen: &[bool]) {
        let samples = &mut self.0.samples;
        let stride = samples.request.len();
        for (field, _) in seen.iter().enumerate().filter(|(_, &seen)| !seen) {
            if samples.optional[field] {
                samples.absent[index * stride + field] = true;
            } else {
                samples.problems.push((index, field, Problem::Missing));
            }
        }
        self.0.stopped = !samples.problems.is_empty();
    }
}

impl<'de> DeserializeSeed<'de> for SampleSeed<'_> {
    type Value = ();
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for SampleSeed<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a sample")
    }
    fn visit_map<A: MapAccess<'de>>(mut self, mut map: A) -> Result<(), A::Error> {
        let index = self.begin();
        let mut names: Vec<&'static str> = self.0.samples.request.iter().map(|&(n, _)| n).collect();
        let fields = names.len();
        if self.0.links.is_some() {
            names.push(F_EXT);
        }
        let mut seen = vec![false; fields];
        while let Some(key) = map.next_key_seed(NameSeed(&names))? {
            match key {
                Some(field) if field == fields => {
                    map.next_value_seed(WrenchesSeed {
                        reader: &mut *self.0,
                        sample: index,
                    })?;
                }
                Some(field) => {
                    seen[field] = true;
                    map.next_value_seed(FieldSeed {
                        reader: &mut *self.0,
                        sample: index,
                        field,
                    })?;
                }
                None => map.next_value::<IgnoredAny>().map(drop)?,
            }
        }
        self.end(index, &seen);
        Ok(())
    }
    fn visit_seq<A: SeqAccess<'de>>(mut self, seq: A) -> Result<(), A::Error> {
        let index = self.begin();
        skip_seq(seq)?;
        self.end(index, &vec![false; self.0.samples.request.len()]);
        Ok(())
    }
    forward_scalars!(|mut this| {
        let index = this.begin();
        this.end(index, &vec![false; this.0.samples.request.len()]);
        Ok(())
    });
}

/// How many entries past a field's length are counted before it is refused (a free-floating base adds 7
/// to `q`; one more tells that state from a longer one).
pub(crate) const EXTRA_COUNTED: usize = 8;

/// A requested field of one sample: an array of exactly the needed number of finite numbers.
struct FieldSeed<'a> {
    reader: &'a mut Reader,
    sample: usize,
    field: usize,
}

impl FieldSeed<'_> {
    /// Refuses the field for its length: `given` entries, exactly or at least.
    fn too_many<E: de::Error>(&mut self, len: usize, given: usize, exact: bool) -> E {
        let (sample, field) = (self.sample, self.reader.samples.request[self.field].0);
        self.reader.refuse(InputError::TooManyEntries {
            sample,
            field,
            len,
            given,
            exact,
            hint: "",
        })
    }

    /// Replaces what is recorded about this field (a repeated key replaces the earlier value).
    fn record(&mut self, problem: Option<Problem>) {
        let (sample, field) = (self.sample, self.field);
        let problems = &mut self.reader.samples.problems;
        problems.retain(|&(s, f, _)| (s, f) != (sample, field));
        if let Some(problem) = problem {
            problems.push((sample, field, problem));
        }
    }
}

impl<'de> DeserializeSeed<'de> for FieldSeed<'_> {
    type Value = ();
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for FieldSeed<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("an array of numbers")
    }
    fn visit_seq<A: SeqAccess<'de>>(mut self, mut seq: A) -> Result<(), A::Error> {
        let len = self.reader.samples.request[self.field].1;
        let start =
            self.sample * self.reader.samples.stride + self.reader.samples.offsets[self.field];
        let mut count = 0;
        let mut first_bad = None;
        while let Some(entry) = seq.next_element::<Entry>()? {
            if count >= len {
                // Entries past the model's length are counted, not kept, up to EXTRA_COUNTED more: the
                // message then gives the length (a floating base's state is 7 longer in `q`), and the
                // reading still stops within a few entries of the model's length.
                if count == len + EXTRA_COUNTED {
                    return Err(self.too_many(len, count, false));
                }
                count += 1;
                continue;
            }
            match entry {
                Entry::Number(x) if x.is_finite() => self.reader.samples.numbers[start + count] = x,
                Entry::Number(x) => {
                    first_bad.get_or_insert_with(|| (count, x.to_string()));
                }
                Entry::Other(shown) => {
                    first_bad.get_or_insert((count, shown));
                }
            }
            count += 1;
        }
        if count > len {
            return Err(self.too_many(len, count, true));
        }
        // The length is judged before the entries, as it always was.
        let problem = if count < len {
            Some(Problem::Short(count))
        } else {
            first_bad.map(|(index, shown)| Problem::NotFinite { index, shown })
        };
        self.record(problem);
        Ok(())
    }
    fn visit_map<A: MapAccess<'de>>(mut self, map: A) -> Result<(), A::Error> {
        skip_map(map)?;
        self.record(Some(Problem::NotArray));
        Ok(())
    }
    forward_scalars!(|mut this| {
        this.record(Some(Problem::NotArray));
        Ok(())
    });
}

/// A sample's `f_ext`: an object of link names to wrenches. The first problem is recorded and the rest
/// of the object skipped.
struct WrenchesSeed<'a> {
    reader: &'a mut Reader,
    sample: usize,
}

impl WrenchesSeed<'_> {
    /// Replaces what is recorded about this sample's `f_ext` (a repeated key replaces the earlier
    /// value, as for any field).
    fn record(&mut self, problem: Option<Problem>) {
        let (sample, field) = (self.sample, self.reader.samples.request.len());
        let problems = &mut self.reader.samples.problems;
        problems.retain(|&(s, f, _)| (s, f) != (sample, field));
        if let Some(problem) = problem {
            problems.push((sample, field, problem));
        }
    }

    /// Forgets this sample's wrenches read so far.
    fn clear(&mut self) {
        let samples = &mut self.reader.samples;
        let start = samples.wrench_starts[self.sample];
        samples.wrenches.truncate(start);
    }
}

impl<'de> DeserializeSeed<'de> for WrenchesSeed<'_> {
    type Value = ();
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for WrenchesSeed<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("external wrenches")
    }
    fn visit_map<A: MapAccess<'de>>(mut self, mut map: A) -> Result<(), A::Error> {
        self.clear();
        self.record(None);
        let Some(links) = self.reader.links.as_mut() else {
            return skip_map(map);
        };
        links.stamp += 1;
        while let Some(key) = map.next_key_seed(LinkSeed(&*links))? {
            let problem = match key {
                LinkKey::Known(frame) if links.stamps[frame] == links.stamp => {
                    map.next_value::<IgnoredAny>()?;
                    Problem::DuplicateLink(links.names[frame].clone())
                }
                LinkKey::Known(frame) => {
                    links.stamps[frame] = links.stamp;
                    match map.next_value_seed(WrenchSeed)? {
                        Ok((force, torque)) => {
                            self.reader.samples.wrenches.push(Wrench {
                                frame,
                                force,
                                torque,
                            });
                            continue;
                        }
                        Err(problem) => problem.on(&links.names[frame]),
                    }
                }
                LinkKey::Unknown(link) => {
                    map.next_value::<IgnoredAny>()?;
                    let suggestions =
                        crate::suggest::close_names(&link, links.names.iter().map(String::as_str));
                    Problem::UnknownLink { link, suggestions }
                }
            };
            self.clear();
            self.record(Some(problem));
            return skip_map(map);
        }
        Ok(())
    }
    fn visit_seq<A: SeqAccess<'de>>(mut self, seq: A) -> Result<(), A::Error> {
        skip_seq(seq)?;
        self.clear();
        self.record(Some(Problem::NotWrenches));
        Ok(())
    }
    forward_scalars!(|mut this| {
        this.clear();
        this.record(Some(Problem::NotWrenches));
        Ok(())
    });
}

/// A key of `f_ext`: a link of the model (its frame index) or another name (kept for the message).
enum LinkKey {
    Known(usize),
    Unknown(String),
}

struct LinkSeed<'a>(&'a LinkTable);

impl<'de> DeserializeSeed<'de> for LinkSeed<'_> {
    type Value = LinkKey;
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<LinkKey, D::Error> {
        d.deserialize_str(self)
    }
}

impl<'de> Visitor<'de> for LinkSeed<'_> {
    type Value = LinkKey;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a link name")
    }
    fn visit_str<E>(self, key: &str) -> Result<LinkKey, E> {
        Ok(match self.0.index.get(key) {
            Some(&frame) => LinkKey::Known(frame),
            // Kept whole for the message (which shortens it): one copy, once, as the read stops there.
            None => LinkKey::Unknown(key.to_string()),
        })
    }
}

/// What is wrong with one link's wrench (the link is added by [`WrenchProblem::on`]).
enum WrenchProblem {
    NotObject,
    Part(&'static str, WrenchPartProblem),
}

impl WrenchProblem {
    fn on(self, link: &str) -> Problem {
        match self {
            WrenchProblem::NotObject => Problem::WrenchNotObject(link.to_string()),
            WrenchProblem::Part(part, problem) => Problem::WrenchPart {
                link: link.to_string(),
                part,
                problem,
            },
        }
    }
}

type WrenchRead = Result<([f64; 3], [f64; 3]), WrenchProblem>;

/// One link's wrench: `{"force": [3], "torque": [3]}`, both required, other keys ignored (a repeated
/// key replaces the earlier value).
struct WrenchSeed;

const WRENCH_PARTS: [&str; 2] = ["force", "torque"];

impl<'de> DeserializeSeed<'de> for WrenchSeed {
    type Value = WrenchRead;
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<WrenchRead, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for WrenchSeed {
    type Value = WrenchRead;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a wrench")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<WrenchRead, A::Error> {
        let mut parts: [Option<Result<[f64; 3], WrenchPartProblem>>; 2] = [None, None];
        while let Some(key) = map.next_key_seed(NameSeed(&WRENCH_PARTS))? {
            match key {
                Some(k) => parts[k] = Some(map.next_value_seed(Vector3Seed)?),
                None => map.next_value::<IgnoredAny>().map(drop)?,
            }
        }
        let [force, torque] = parts;
        let part = |k: usize, p: Option<Result<[f64; 3], WrenchPartProblem>>| match p {
            None => Err(WrenchProblem::Part(
                WRENCH_PARTS[k],
                WrenchPartProblem::Missing,
            )),
            Some(Err(problem)) => Err(WrenchProblem::Part(WRENCH_PARTS[k], problem)),
            Some(Ok(x)) => Ok(x),
        };
        Ok(part(0, force).and_then(|f| Ok((f, part(1, torque)?))))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<WrenchRead, A::Error> {
        skip_seq(seq)?;
        Ok(Err(WrenchProblem::NotObject))
    }
    forward_scalars!(|_this| { Ok(Err(WrenchProblem::NotObject)) });
}

/// A force or torque: exactly three finite numbers (more are counted, not stored).
struct Vector3Seed;

impl<'de> DeserializeSeed<'de> for Vector3Seed {
    type Value = Result<[f64; 3], WrenchPartProblem>;
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Vector3Seed {
    type Value = Result<[f64; 3], WrenchPartProblem>;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("three numbers")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut x = [0.0; 3];
        let mut count = 0usize;
        let mut first_bad = None;
        while let Some(entry) = seq.next_element::<Entry>()? {
            match entry {
                Entry::Number(value) if value.is_finite() => {
                    if let Some(slot) = x.get_mut(count) {
                        *slot = value;
                    }
                }
                Entry::Number(value) => {
                    first_bad.get_or_insert_with(|| (count, value.to_string()));
                }
                Entry::Other(shown) => {
                    first_bad.get_or_insert((count, shown));
                }
            }
            count += 1;
        }
        Ok(match first_bad {
            _ if count != 3 => Err(WrenchPartProblem::Length { got: count }),
            Some((index, shown)) => Err(WrenchPartProblem::NotFinite { index, shown }),
            None => Ok(x),
        })
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        skip_map(map)?;
        Ok(Err(WrenchPartProblem::NotArray))
    }
    forward_scalars!(|_this| { Ok(Err(WrenchPartProblem::NotArray)) });
}

/// One entry of a requested field: a number, or anything else as it is shown in a message (a nested
/// array or object is skipped, not stored, and shown abbreviated).
enum Entry {
    Number(f64),
    Other(String),
}

impl<'de> de::Deserialize<'de> for Entry {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(EntryVisitor)
    }
}

struct EntryVisitor;

impl<'de> Visitor<'de> for EntryVisitor {
    type Value = Entry;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number")
    }
    fn visit_f64<E>(self, x: f64) -> Result<Entry, E> {
        Ok(Entry::Number(x))
    }
    fn visit_i64<E>(self, x: i64) -> Result<Entry, E> {
        Ok(Entry::Number(x as f64))
    }
    fn visit_u64<E>(self, x: u64) -> Result<Entry, E> {
        Ok(Entry::Number(x as f64))
    }
    fn visit_bool<E>(self, x: bool) -> Result<Entry, E> {
        Ok(Entry::Other(x.to_string()))
    }
    fn visit_unit<E>(self) -> Result<Entry, E> {
        Ok(Entry::Other("null".into()))
    }
    fn visit_str<E: de::Error>(self, x: &str) -> Result<Entry, E> {
        serde_json::to_string(x)
            .map(Entry::Other)
            .map_err(E::custom)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Entry, A::Error> {
        skip_seq(seq)?;
        Ok(Entry::Other("[...]".into()))
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Entry, A::Error> {
        skip_map(map)?;
        Ok(Entry::Other("{...}".into()))
    }
}

/// A key, as its index in `names` (`None`: a key that is not read). Compared in place, never stored.
struct NameSeed<'n>(&'n [&'static str]);

impl<'de> DeserializeSeed<'de> for NameSeed<'_> {
    type Value = Option<usize>;
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Option<usize>, D::Error> {
        d.deserialize_str(self)
    }
}

impl<'de> Visitor<'de> for NameSeed<'_> {
    type Value = Option<usize>;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a field name")
    }
    fn visit_str<E>(self, key: &str) -> Result<Option<usize>, E> {
        Ok(self.0.iter().position(|&name| name == key))
    }
}

fn skip_seq<'de, A: SeqAccess<'de>>(mut seq: A) -> Result<(), A::Error> {
    while seq.next_element::<IgnoredAny>()?.is_some() {}
    Ok(())
}

fn skip_map<'de, A: MapAccess<'de>>(mut map: A) -> Result<(), A::Error> {
    while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_problem_is_reported_as_data_with_the_same_message() {
        let request = [("q", 3), ("v", 2)];
        let short = Samples::parse(r#"{"samples": [{"q": [1, 2], "v": [0, 0]}]}"#, &request)
            .unwrap()
            .vector(0, "q")
            .unwrap_err();
        assert!(matches!(
            &short,
            CliError::Sample { sample: 0, field, problem: SampleProblem::Length { got: 2, expected: 3 } }
                if field == "q"
        ));
        assert_eq!(
            short.to_string(),
            "sample 0: field `q` has 2 entries, the model needs 3"
        );
        let missing = Samples::parse(r#"{"samples": [{"q": [1, 2, 3]}]}"#, &request)
            .unwrap()
            .vector(0, "v")
            .unwrap_err();
        assert!(matches!(
            &missing,
            CliError::Sample {
                sample: 0,
                problem: SampleProblem::Missing,
                ..
            }
        ));
        assert_eq!(missing.to_string(), "sample 0: missing field `v`");
    }
}

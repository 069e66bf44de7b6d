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

use super::{CliError, InputError, InternalError, SampleProblem};
use serde::de::{self, DeserializeSeed, IgnoredAny, MapAccess, SeqAccess, Visitor};
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

/// The samples of an input: `len()` samples, each with the requested fields.
pub struct Samples {
    request: Vec<(&'static str, usize)>,
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
}

impl Samples {
    /// Reads `text`, keeping the fields of `request` of every sample.
    pub fn parse(text: &str, request: &Request) -> Result<Self, CliError> {
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
            },
            root: Root::NoSamples,
            stopped: false,
            refusal: None,
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
                self.vector(index, name)?;
            }
        }
        Ok(())
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
                problem: match problem {
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
                },
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
        index
    }

    /// Records every requested field not in `seen` as missing; after a sample with a problem the read
    /// stops keeping samples.
    fn end(&mut self, index: usize, seen: &[bool]) {
        let problems = &mut self.0.samples.problems;
        for (field, _) in seen.iter().enumerate().filter(|(_, &seen)| !seen) {
            problems.push((index, field, Problem::Missing));
        }
        self.0.stopped = !problems.is_empty();
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
        let names: Vec<&'static str> = self.0.samples.request.iter().map(|&(n, _)| n).collect();
        let mut seen = vec![false; names.len()];
        while let Some(key) = map.next_key_seed(NameSeed(&names))? {
            match key {
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

/// A requested field of one sample: an array of exactly the needed number of finite numbers.
struct FieldSeed<'a> {
    reader: &'a mut Reader,
    sample: usize,
    field: usize,
}

impl FieldSeed<'_> {
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
        let (name, len) = self.reader.samples.request[self.field];
        let start =
            self.sample * self.reader.samples.stride + self.reader.samples.offsets[self.field];
        let mut count = 0;
        let mut first_bad = None;
        while let Some(entry) = seq.next_element::<Entry>()? {
            if count == len {
                let sample = self.sample;
                return Err(self.reader.refuse(InputError::TooManyEntries {
                    sample,
                    field: name,
                    len,
                }));
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

//! [`WireMessage`], everything the wire crate knows of one TSP/1 message type: its type code and
//! name, its payload layout (minimum length, parse, write), its form in the CSV dialect (§6) and
//! its test vector. Each message implements it in its own file; `mod.rs` registers them.

use std::io::Write;

use super::super::payload::Writer;

/// A message's command line in the CSV dialect (§6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsvCommandForm {
    /// No command line (device → host messages, or a command the dialect lacks).
    None,
    /// Written as `<keyword> <args>`, and that keyword reads back as this message.
    Reads(&'static str),
    /// Written as this keyword, which reads back as another message (HEARTBEAT as `PING`).
    WritesAs(&'static str),
}

impl CsvCommandForm {
    /// The keyword the message is written as.
    pub fn keyword(self) -> Option<&'static str> {
        match self {
            Self::None => None,
            Self::Reads(k) | Self::WritesAs(k) => Some(k),
        }
    }

    /// True when `keyword` reads back as this message.
    pub fn reads(self, keyword: &str) -> bool {
        matches!(self, Self::Reads(k) if k == keyword)
    }
}

/// Why a command line's arguments do not read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsvArgError {
    /// A required argument is missing.
    Missing,
    /// An argument is not a whole number or out of its field's range.
    Bad,
}

/// The words after a command line's keyword.
pub struct CsvArgs<'a> {
    words: std::str::SplitWhitespace<'a>,
}

impl<'a> CsvArgs<'a> {
    /// The words of `rest` (the line after its keyword).
    pub fn new(words: std::str::SplitWhitespace<'a>) -> Self {
        Self { words }
    }
    /// The next word, which must be there.
    pub fn required(&mut self) -> Result<&'a str, CsvArgError> {
        self.words.next().ok_or(CsvArgError::Missing)
    }
    /// The next word, if any.
    pub fn optional(&mut self) -> Option<&'a str> {
        self.words.next()
    }
    /// A whole number that fits a `u16`.
    pub fn u16(w: &str) -> Result<u16, CsvArgError> {
        u16::try_from(Self::u64(w)?).map_err(|_| CsvArgError::Bad)
    }
    /// A whole number that fits a `u32`.
    pub fn u32(w: &str) -> Result<u32, CsvArgError> {
        u32::try_from(Self::u64(w)?).map_err(|_| CsvArgError::Bad)
    }
    fn u64(w: &str) -> Result<u64, CsvArgError> {
        w.parse().map_err(|_| CsvArgError::Bad)
    }
}

/// A message's test vector: the frame with link sequence `seq` is `wire` (hex bytes, spaces
/// ignored), and its CSV line (without newline) `csv`, if it has one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vector<M> {
    /// Link sequence number.
    pub seq: u16,
    /// The message.
    pub msg: M,
    /// The encoded frame, delimiter included, as hex bytes.
    pub wire: &'static str,
    /// The CSV line (a command or a device line), `None` when it has none.
    pub csv: Option<&'static str>,
}

/// One TSP/1 message type (docs/PROTOCOL.md §3, §4, §6). A payload-less command is a unit
/// struct whose `Message` variant carries nothing.
pub trait WireMessage: Sized {
    /// The type code (`type` byte of the frame body).
    const TYPE: u8;
    /// The protocol name (`"SAMPLE"`, `"SET_THROTTLE"`, …).
    const NAME: &'static str;
    /// The minimum payload length; trailing bytes are ignored (fields may only be appended).
    const MIN_LEN: usize;
    /// Its command line in the CSV dialect.
    const CSV_COMMAND: CsvCommandForm = CsvCommandForm::None;

    /// Reads a payload of at least [`MIN_LEN`](Self::MIN_LEN) bytes.
    fn parse(p: &[u8]) -> Self;

    /// Writes the payload.
    fn write(&self, w: &mut Writer<'_>);

    /// Writes the arguments of its CSV command line (each with its leading space).
    fn write_csv_args(&self, _w: &mut dyn Write) -> std::io::Result<()> {
        Ok(())
    }

    /// Reads the arguments of its CSV command line (for [`CsvCommandForm::Reads`]): all the
    /// words it needs first (one missing is [`CsvArgError::Missing`]), then their numbers.
    fn parse_csv_args(_args: &mut CsvArgs<'_>) -> Result<Self, CsvArgError> {
        Err(CsvArgError::Missing)
    }

    /// Appends the line a CSV bench writes for it (without newline); false when it has none.
    fn write_csv_line(&self, _s: &mut String) -> bool {
        false
    }

    /// Reads its device line back from a comment's text (after `#`), when the dialect reads it.
    fn read_csv_line(_text: &str) -> Option<Self> {
        None
    }

    /// Its test vector (docs/PROTOCOL.md §5 where the specification gives one).
    fn vector() -> Vector<Self>;
}

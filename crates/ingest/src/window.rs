//! A binary TSP/1 recording longer than the identification window, read in bounded memory:
//! the span of [`WINDOW_SAMPLES`] rows `identify` reports on, chosen in a first pass over the
//! file, kept in a second ([`Scan`], then the [`BinaryReader`] it gives).
//!
//! First pass: the file is decoded as [`BinaryReader`] decodes it; while it has at most
//! [`WINDOW_SAMPLES`] rows it is built whole (a short recording reads exactly as before, in one
//! pass); past that, its rows are handed over as they come and only the command (the input
//! channel) is looked at: its moves are counted per block (a [`BLOCKS_PER_WINDOW`]th of the window). A move
//! is a change of more than [`MOVE_SHARE`] of the command's range over the whole file from one
//! row to the next (missing rows hold the last command), the rule the stand fit uses to place
//! its rows (`propid_numerics::stand_model::fit`, long records). The range is only known at the
//! end: changes larger than that share of the range seen so far are kept per block (the range
//! only widens, so a smaller change is never a move), and counted against the final range at
//! the end. A command that changes on so many rows that these changes would exceed
//! [`MAX_CHANGES`] takes a second counting pass with the range known ([`Scanned::Rescan`]).
//!
//! The window: the [`WINDOW_SAMPLES`] rows starting on a block boundary whose blocks hold the
//! most moves (the earliest of equals; the first rows without a command channel). Second
//! pass: the file is decoded again and only the window's rows are stored
//! ([`RecordBuilder::keep`]); every counter is the whole file's, and the record says which span
//! it is ([`RecordWindow`]). Memory: the window's rows and one counter per block.

pub use crate::tsp::RecordWindow;
use crate::tsp::{BinaryReader, IngestOptions, IngestStats};
use propid_wire::record::Record;
use propid_wire::stream::assemble::CHANNELS;
use propid_wire::stream::IngestError;

/// Rows `identify` reads of a binary recording: about 2 min at 1 kHz.
pub const WINDOW_SAMPLES: usize = 1 << 17;
/// Blocks of the move count in a window (the window's start moves by a block).
pub const BLOCKS_PER_WINDOW: usize = 16;
pub use propid_numerics::stand_model::spans::MOVE_SHARE;
/// Most changes the first pass keeps before it counts in a pass of its own (8 MB).
pub const MAX_CHANGES: usize = 1 << 20;

/// The command's moves per block, from the command's rows as they come.
#[derive(Debug, Clone)]
pub struct MoveCounter {
    /// The final range, when known (a counting pass).
    range: Option<f64>,
    lo: f64,
    hi: f64,
    prev: Option<f64>,
    pos: usize,
    /// Per block: the moves (a counting pass), or the changes over the share of the range so
    /// far (a first pass).
    counts: Vec<usize>,
    changes: Vec<Vec<f64>>,
    kept: usize,
    overflowed: bool,
    /// Rows a block.
    block: usize,
    /// Most changes kept ([`MAX_CHANGES`]).
    cap: usize,
}

impl MoveCounter {
    /// A first pass (`range` unknown) or a counting pass (`range`: the command's, over the
    /// file), in blocks of `block` rows.
    pub fn new(range: Option<f64>, block: usize) -> Self {
        MoveCounter {
            range,
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
            prev: None,
            pos: 0,
            counts: Vec::new(),
            changes: Vec::new(),
            kept: 0,
            overflowed: false,
            block: block.max(1),
            cap: MAX_CHANGES,
        }
    }

    /// Rows seen.
    pub fn len(&self) -> usize {
        self.pos
    }

    /// True before the first row.
    pub fn is_empty(&self) -> bool {
        self.pos == 0
    }

    /// The next rows of the command (NaN: missing, the last command holds).
    pub fn push(&mut self, u: &[f64]) {
        for &v in u {
            let b = self.pos / self.block;
            self.pos += 1;
            if !v.is_finite() {
                continue;
            }
            self.lo = self.lo.min(v);
            self.hi = self.hi.max(v);
            let Some(p) = self.prev.replace(v) else {
                continue;
            };
            let d = (v - p).abs();
            if d == 0.0 {
                continue;
            }
            match self.range {
                Some(r) => {
                    if d > MOVE_SHARE * r {
                        grow(&mut self.counts, b);
                        self.counts[b] += 1;
                    }
                }
                None if self.overflowed => {}
                None => {
                    if d > MOVE_SHARE * (self.hi - self.lo) {
                        if self.changes.len() <= b {
                            self.changes.resize_with(b + 1, Vec::new);
                        }
                        self.changes[b].push(d);
                        self.kept += 1;
                        if self.kept > self.cap {
                            self.compact();
                        }
                    }
                }
            }
        }
    }

    /// Drops the changes the range seen so far already rules out; gives up keeping them when
    /// more than half remain.
    fn compact(&mut self) {
        let t = MOVE_SHARE * (self.hi - self.lo);
        for c in &mut self.changes {
            c.retain(|&d| d > t);
        }
        self.kept = self.changes.iter().map(Vec::len).sum();
        if self.kept > self.cap / 2 {
            self.overflowed = true;
            self.changes = Vec::new();
            self.kept = 0;
        }
    }

    /// The command's range so far (0 without a finite row).
    pub fn range(&self) -> f64 {
        if self.hi >= self.lo {
            self.hi - self.lo
        } else {
            0.0
        }
    }

    /// The moves per block, or `None` when a counting pass is needed (the first pass gave up
    /// keeping the changes).
    pub fn moves(&self) -> Option<Vec<usize>> {
        let blocks = self.pos.div_ceil(self.block);
        if self.range.is_some() {
            let mut c = self.counts.clone();
            c.resize(blocks, 0);
            return Some(c);
        }
        if self.overflowed {
            return None;
        }
        let t = MOVE_SHARE * self.range();
        let mut c: Vec<usize> = self
            .changes
            .iter()
            .map(|c| c.iter().filter(|&&d| d > t).count())
            .collect();
        c.resize(blocks, 0);
        Some(c)
    }
}

fn grow(v: &mut Vec<usize>, b: usize) {
    if v.len() <= b {
        v.resize(b + 1, 0);
    }
}

/// The start of the window of `window` rows (a multiple of `block`) in `len` rows whose
/// blocks (of `block` rows, `moves` per block) hold the most moves, the earliest of equals;
/// with the moves in it. `len ≤ window`: 0.
pub fn choose_window(moves: &[usize], len: usize, window: usize, block: usize) -> (usize, usize) {
    let block = block.max(1);
    let per = (window / block).max(1);
    let in_blocks = |j: usize| moves.iter().skip(j).take(per).sum::<usize>();
    if len <= window {
        return (0, in_blocks(0));
    }
    let last = (len - window) / block;
    let mut best = (0, in_blocks(0));
    let mut sum = best.1;
    for j in 1..=last {
        sum = sum + moves.get(j + per - 1).copied().unwrap_or(0) - moves[j - 1];
        if sum > best.1 {
            best = (j, sum);
        }
    }
    (best.0 * block, best.1)
}

/// The first pass over a binary recording (see the module documentation).
pub struct Scan {
    reader: BinaryReader,
    counter: MoveCounter,
    /// The command's index in [`CHANNELS`] (`None`: no command channel asked for).
    command: Option<usize>,
    window: usize,
    /// Whether the rows are handed over (the file is longer than the window).
    spilled: bool,
    opts: IngestOptions,
}

/// What the first pass found.
#[allow(clippy::large_enum_variant)]
pub enum Scanned {
    /// The file fits the window: its record, read as [`BinaryReader`] reads it.
    Whole(Record, IngestStats),
    /// The command changed too often to keep its changes: decode again, counting.
    Rescan(Scan),
    /// Decode again with this reader: it keeps the window's rows only.
    Window(BinaryReader),
}

impl Scan {
    /// A first pass with `o`'s options; `command`: the input channel's name ([`CHANNELS`]),
    /// `None` when there is none; `window`: rows kept ([`WINDOW_SAMPLES`]; a multiple of
    /// [`BLOCKS_PER_WINDOW`]).
    pub fn new(o: &IngestOptions, command: Option<&str>, window: usize) -> Self {
        let window = window.max(BLOCKS_PER_WINDOW);
        Scan {
            reader: BinaryReader::new(o),
            counter: MoveCounter::new(None, window / BLOCKS_PER_WINDOW),
            command: command.and_then(|n| CHANNELS.iter().position(|c| c.0 == n)),
            window,
            spilled: false,
            opts: *o,
        }
    }

    /// The next bytes of the recording.
    pub fn push(&mut self, bytes: &[u8]) {
        self.reader.push(bytes);
        if self.spilled || self.reader.builder().len() > self.window {
            self.spilled = true;
            let rows = self.reader.builder_mut().take_rows();
            if let Some(c) = self.command.filter(|_| rows.present.is_some()) {
                self.counter.push(&rows.data[c]);
            } else {
                self.counter.push(&vec![f64::NAN; rows.missing.len()]);
            }
        }
    }

    /// The file's end: its record when it fits the window, else the next pass.
    pub fn finish(mut self) -> Result<Scanned, IngestError> {
        if !self.spilled {
            let (record, stats) = self.reader.finish()?;
            return Ok(Scanned::Whole(record, stats));
        }
        self.push(&[]);
        let Some(moves) = self.counter.moves() else {
            let mut again = Scan::new(&self.opts, None, self.window);
            again.command = self.command;
            again.counter = MoveCounter::new(Some(self.counter.range()), self.counter.block);
            return Ok(Scanned::Rescan(again));
        };
        let len = self.counter.len();
        let (start, in_window) = choose_window(&moves, len, self.window, self.counter.block);
        let mut reader = BinaryReader::new(&self.opts);
        reader.builder_mut().keep(start, start + self.window);
        reader.moves = Some((in_window, moves.iter().sum()));
        Ok(Scanned::Window(reader))
    }
}

#[cfg(test)]
mod tests;

//! What a reader did not keep.

use std::collections::HashMap;
use std::fmt;

use serde::{Deserialize, Serialize};

use super::{Format, Location, PlyEncoding};

/// One kind of data found in a file and not kept in the soup.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DroppedAttribute {
    /// What it is, in words (e.g. "normals (`vn`)", "PLY vertex property `red`").
    pub what: String,
    /// How many were dropped (lines, values or elements, as `what` says).
    pub count: usize,
    /// Where the first one is.
    pub first: Location,
}

/// What a reader found besides positions and faces.
///
/// Lists every attribute the soup cannot hold, in order of first appearance in the file.
/// An empty list means the soup holds everything the file says.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ReadReport {
    /// The format read.
    pub format: Format,
    /// The encoding, for PLY files.
    pub ply_encoding: Option<PlyEncoding>,
    /// What was not kept.
    pub dropped: Vec<DroppedAttribute>,
}

impl ReadReport {
    /// True if the soup holds everything the file contains.
    ///
    /// ```
    /// use mesh_topo::io::{self, Format};
    ///
    /// let (_, report) = io::read_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", Format::Obj)?;
    /// assert!(report.is_lossless());
    /// // A texture coordinate the soup cannot hold.
    /// let (_, report) = io::read_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1 2 3\n", Format::Obj)?;
    /// assert!(!report.is_lossless());
    /// assert_eq!(report.dropped[0].count, 1);
    /// # Ok::<(), mesh_topo::io::IoError>(())
    /// ```
    pub fn is_lossless(&self) -> bool {
        self.dropped.is_empty()
    }
}

impl fmt::Display for ReadReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.dropped.is_empty() {
            return f.write_str("nothing dropped");
        }
        for (i, dropped) in self.dropped.iter().enumerate() {
            if i > 0 {
                f.write_str("; ")?;
            }
            write!(f, "{dropped}")?;
        }
        Ok(())
    }
}

impl fmt::Display for DroppedAttribute {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} x {} (first at {})", self.count, self.what, self.first)
    }
}

/// Collects dropped attributes by name, keeping the order of first appearance.
#[derive(Default)]
pub(crate) struct DroppedLog {
    entries: Vec<DroppedAttribute>,
    by_name: HashMap<String, usize>,
}

impl DroppedLog {
    /// Counts `count` more of `what`, first seen at `at` if new.
    pub(crate) fn add(&mut self, what: &str, count: usize, at: Location) {
        if count == 0 {
            return;
        }
        match self.by_name.get(what) {
            Some(&i) => self.entries[i].count += count,
            None => {
                self.by_name.insert(what.to_string(), self.entries.len());
                self.entries.push(DroppedAttribute { what: what.to_string(), count, first: at });
            }
        }
    }

    /// Adds the entries of `later`, a log of lines after all of this one's.
    pub(crate) fn merge(&mut self, later: DroppedLog) {
        for entry in later.entries {
            self.add(&entry.what, entry.count, entry.first);
        }
    }

    pub(crate) fn into_report(self, format: Format, ply_encoding: Option<PlyEncoding>) -> ReadReport {
        let mut dropped = self.entries;
        // Entries are already in order of first appearance; sort anyway by location so
        // counters flushed at the end (see the OBJ reader) fall into place.
        dropped.sort_by_key(|d| match d.first {
            Location::Line(l) | Location::Byte(l) => l,
        });
        ReadReport { format, ply_encoding, dropped }
    }
}

/// A counter for one frequent kind of dropped data, cheaper than a map lookup per line.
#[derive(Default, Clone, Copy)]
pub(crate) struct Counter {
    pub(crate) count: usize,
    pub(crate) first: usize,
}

impl Counter {
    #[inline]
    pub(crate) fn hit(&mut self, line: usize) {
        if self.count == 0 {
            self.first = line;
        }
        self.count += 1;
    }

    /// Adds the hits of `later`, a counter of lines after all of this one's.
    pub(crate) fn merge(&mut self, later: Counter) {
        if self.count == 0 {
            self.first = later.first;
        }
        self.count += later.count;
    }

    pub(crate) fn flush(self, log: &mut DroppedLog, what: &str) {
        log.add(what, self.count, Location::Line(self.first));
    }
}

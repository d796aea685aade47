//! Where each part of the resolved document was written. Includes, templates and merging move
//! entries around, so every problem is located through [`Origins`]: a path into the resolved
//! document is mapped back to a file and a path into that file as written, whose line is then
//! looked up there (so lines added by overrides never shift numbers).

use super::overrides::Seg;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use toml_edit::{Document, Item, TableLike, Value};

/// One launch file as read from disk.
#[derive(Debug)]
pub struct Source {
    /// As named on the command line or joined to the including file's directory.
    pub path: PathBuf,
    /// The directory relative paths in the file are relative to (empty: the current one).
    pub dir: PathBuf,
    /// `dir`, absolute: handed to processes as `CARAVAN_LAUNCH_DIR`.
    pub abs_dir: PathBuf,
    /// The order in which files were read (0 = the top file); problems are listed in it.
    pub rank: usize,
    pub original: Document<String>,
}

/// Why a file could not be used at all.
pub enum ReadFailure {
    Io(String),
    /// A syntax error: location (`file:line:col`), line and message.
    Syntax(String, usize, String),
}

impl Source {
    pub fn read(path: &Path, rank: usize) -> Result<Source, ReadFailure> {
        let text =
            caravan::input::read_to_string(path).map_err(|e| ReadFailure::Io(e.to_string()))?;
        Self::parse(path, text, rank)
    }

    /// A file's `text` as if read from `path` (a recording's resolved launch file, put back
    /// in the directory of the file it came from).
    pub fn parse(path: &Path, text: String, rank: usize) -> Result<Source, ReadFailure> {
        let original = Document::parse(text.clone()).map_err(|e| syntax_error(path, &text, &e))?;
        let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
        let base = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            &dir
        };
        let abs_dir = std::path::absolute(base).unwrap_or_else(|_| base.to_path_buf());
        Ok(Source {
            path: path.to_path_buf(),
            dir,
            abs_dir,
            rank,
            original,
        })
    }

    /// `file:line`, or just the file without a line.
    pub fn at(&self, line: Option<usize>) -> String {
        match line {
            Some(l) => format!("{}:{l}", self.path.display()),
            None => self.path.display().to_string(),
        }
    }

    /// The line of the deepest part of `path` found in the file as written.
    pub fn line_of(&self, path: &[Seg]) -> Option<usize> {
        let mut table: &dyn TableLike = self.original.as_table();
        let mut offset = None;
        let mut segs = path.iter().peekable();
        while let Some(Seg::Key(k)) = segs.next() {
            let Some((key, item)) = table.get_key_value(k) else {
                break;
            };
            offset = key
                .span()
                .or_else(|| item.span())
                .map(|s| s.start)
                .or(offset);
            let next: Option<&dyn TableLike> = match (segs.peek(), item) {
                (Some(Seg::Index(i)), Item::ArrayOfTables(a)) => {
                    segs.next();
                    a.get(*i).map(|t| {
                        offset = t.span().map(|s| s.start).or(offset);
                        t as &dyn TableLike
                    })
                }
                (Some(Seg::Index(i)), Item::Value(Value::Array(a))) => {
                    segs.next();
                    a.get(*i).and_then(|v| {
                        offset = v.span().map(|s| s.start).or(offset);
                        v.as_inline_table().map(|t| t as &dyn TableLike)
                    })
                }
                _ => item.as_table_like(),
            };
            match next {
                Some(t) => table = t,
                None => break,
            }
        }
        offset.map(|o| line_at(self.original.raw(), o))
    }
}

fn syntax_error(path: &Path, text: &str, e: &toml_edit::TomlError) -> ReadFailure {
    let offset = e.span().map_or(0, |s| s.start).min(text.len());
    let line = line_at(text, offset);
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let col = text[line_start..offset].chars().count() + 1;
    ReadFailure::Syntax(
        format!("{}:{line}:{col}", path.display()),
        line,
        format!("TOML syntax error: {}", e.message().trim()),
    )
}

/// The 1-based line of byte `offset` in `text`.
pub fn line_at(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Where one part of the resolved document came from.
#[derive(Debug, Clone)]
pub enum Origin {
    /// Written in `source` at `path`; `note` says which repetition of a template it is.
    File {
        source: Rc<Source>,
        path: Vec<Seg>,
        note: Option<String>,
    },
    /// Set by an include's `set` entry, which problems are blamed on.
    Set {
        location: String,
        line: usize,
        rank: usize,
    },
}

/// A resolved location: what to print, and the keys problems are ordered by.
#[derive(Debug, Clone, PartialEq)]
pub struct Place {
    pub location: String,
    pub line: Option<usize>,
    pub rank: usize,
}

/// Rules mapping paths of the resolved document to where they were written. The longest
/// matching prefix wins; among equal ones the last added (a `set` applied after the file).
#[derive(Debug, Clone)]
pub struct Origins(Vec<(Vec<Seg>, Origin)>);

impl Origins {
    /// Everything written in `source` where it stands.
    pub fn new(source: &Rc<Source>) -> Self {
        Origins(vec![(
            Vec::new(),
            Origin::File {
                source: source.clone(),
                path: Vec::new(),
                note: None,
            },
        )])
    }

    pub fn push(&mut self, prefix: Vec<Seg>, origin: Origin) {
        self.0.push((prefix, origin));
    }

    /// The rule for `path` and the part of `path` below its prefix.
    fn find<'p>(&self, path: &'p [Seg]) -> (&Origin, &'p [Seg]) {
        // `max_by_key` returns the last of equals: the rule added last.
        let (prefix, origin) = self
            .0
            .iter()
            .filter(|(p, _)| path.starts_with(p))
            .max_by_key(|(p, _)| p.len())
            .expect("the root rule matches every path");
        (origin, &path[prefix.len()..])
    }

    /// The origin of `path` itself, with its path extended to it.
    fn origin_of(&self, path: &[Seg]) -> Origin {
        match self.find(path) {
            (Origin::File { source, path, note }, rest) => Origin::File {
                source: source.clone(),
                path: path.iter().chain(rest).cloned().collect(),
                note: note.clone(),
            },
            (set, _) => set.clone(),
        }
    }

    /// The string written in a file at `path`, before arguments were substituted (`None`
    /// when `path` holds no string there, or a `set` wrote it).
    pub fn written(&self, path: &[Seg]) -> Option<String> {
        let Origin::File { source, path, .. } = self.origin_of(path) else {
            return None;
        };
        let mut item = source.original.as_item();
        for seg in &path {
            item = match seg {
                Seg::Key(k) => item.get(k.as_str())?,
                Seg::Index(i) => item.get(*i)?,
            };
        }
        item.as_str().map(str::to_string)
    }

    pub fn place(&self, path: &[Seg]) -> Place {
        match self.origin_of(path) {
            Origin::File { source, path, .. } => {
                let line = source.line_of(&path);
                Place {
                    location: source.at(line),
                    line,
                    rank: source.rank,
                }
            }
            Origin::Set {
                location,
                line,
                rank,
            } => Place {
                location,
                line: Some(line),
                rank,
            },
        }
    }

    /// The file that wrote the entry at `path` (a `set` cannot replace a whole entry), and
    /// which template repetition it is.
    pub fn entry(&self, path: &[Seg]) -> (Rc<Source>, Option<String>) {
        let file = self
            .0
            .iter()
            .filter(|(p, o)| path.starts_with(p) && matches!(o, Origin::File { .. }))
            .max_by_key(|(p, _)| p.len());
        match file {
            Some((_, Origin::File { source, note, .. })) => (source.clone(), note.clone()),
            _ => unreachable!("the root rule is a file"),
        }
    }

    /// Records that the part of `other` at `from` now stands at `to`: its own origin and the
    /// rules below it.
    pub fn transplant(&mut self, other: &Origins, from: &[Seg], to: &[Seg]) {
        self.push(to.to_vec(), other.origin_of(from));
        for (prefix, origin) in &other.0 {
            if prefix.len() > from.len() && prefix.starts_with(from) {
                let moved = to.iter().chain(&prefix[from.len()..]).cloned().collect();
                self.push(moved, origin.clone());
            }
        }
    }
}

/// Moves every path in `paths` at or below `from` to `to`, keeping the part below.
pub fn moved(paths: &[Vec<Seg>], from: &[Seg], to: &[Seg]) -> Vec<Vec<Seg>> {
    paths
        .iter()
        .filter(|p| p.starts_with(from))
        .map(|p| to.iter().chain(&p[from.len()..]).cloned().collect())
        .collect()
}

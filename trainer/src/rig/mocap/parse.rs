//! The BVH text parser: hierarchy by tokens (any whitespace, any line endings), motion by lines
//! (one frame per line, so a short or long frame is reported on its own line).
//!
//! The hierarchy is parsed with an explicit stack rather than recursion, so a hostile file
//! nested a million joints deep is an ordinary (slow to write, quick to reject) input, not a
//! stack overflow.

use std::collections::HashMap;
use std::path::PathBuf;
use std::str::SplitAsciiWhitespace;

use glam::DVec3;

use super::{Channel, Joint, Mocap};
use crate::text::excerpt;

/// Why a BVH file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum MocapError {
    /// The file could not be read (the error names it and why).
    #[error(transparent)]
    Read(#[from] crate::input::InputError),
    /// The text is not valid BVH.
    #[error("{path}:{line}: {problem}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong there.
        problem: Problem,
    },
}

/// What is wrong at a place in a BVH file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Problem {
    /// A token other than the grammar allows here.
    #[error("expected {expected}, found {}", crate::text::quote(.found))]
    Expected {
        /// What the grammar allows.
        expected: &'static str,
        /// The token found.
        found: String,
    },
    /// The file does not start with `HIERARCHY`, so it is not BVH; its content is not quoted.
    #[error("not a BVH file (it does not start with HIERARCHY)")]
    NotBvh,
    /// The text ends in the middle of the hierarchy or the motion header.
    #[error("the file ends where {expected} should be")]
    UnexpectedEnd {
        /// What the grammar expected.
        expected: &'static str,
    },
    /// A `CHANNELS` entry that is not one of the six BVH channels.
    #[error(
        "unknown channel {} (expected Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation)",
        crate::text::quote(.name)
    )]
    UnknownChannel {
        /// The token.
        name: String,
    },
    /// `CHANNELS` not followed by a count from 0 to 6.
    #[error("CHANNELS must be followed by a count from 0 to 6, found {}", crate::text::quote(.found))]
    BadChannelCount {
        /// The token.
        found: String,
    },
    /// A joint lists the same channel twice.
    #[error("joint {} lists {channel:?} twice", crate::text::quote(.joint))]
    RepeatedChannel {
        /// The joint.
        joint: String,
        /// The channel.
        channel: Channel,
    },
    /// A joint or End Site has two `OFFSET`s, or a joint two `CHANNELS`.
    #[error("{what} given twice in {}", crate::text::quote(.joint))]
    Repeated {
        /// `OFFSET` or `CHANNELS`.
        what: &'static str,
        /// The joint (or `End Site of <joint>`).
        joint: String,
    },
    /// A joint or End Site closed without an `OFFSET`.
    #[error("{} has no OFFSET", crate::text::quote(.joint))]
    MissingOffset {
        /// The joint (or `End Site of <joint>`).
        joint: String,
    },
    /// A number was expected.
    #[error("{} is not a number", crate::text::quote(.token))]
    NotANumber {
        /// The token.
        token: String,
    },
    /// A number is NaN or infinite.
    #[error("{} is not a finite number", crate::text::quote(.token))]
    NonFinite {
        /// The token.
        token: String,
    },
    /// `Frame Time` is zero or negative, or so small that its frame rate is infinite.
    #[error(
        "Frame Time must be a positive number of seconds with a finite frame rate, found {value:?}"
    )]
    BadFrameTime {
        /// The value given.
        value: f64,
    },
    /// Two joints share a name (joint names identify channels and retargeting).
    #[error("joint name {} is used twice (first on line {first_line})", crate::text::quote(.name))]
    DuplicateJoint {
        /// The name.
        name: String,
        /// Where it was first declared.
        first_line: usize,
    },
    /// A `{` never closed before `MOTION` or the end of the file.
    #[error("the '{{' of {} on line {opened} is never closed", crate::text::quote(.joint))]
    UnclosedBrace {
        /// The joint (or `End Site of <joint>`) whose brace is open.
        joint: String,
        /// Line of the `{`.
        opened: usize,
    },
    /// A `}` outside every joint.
    #[error("'}}' closes nothing")]
    StrayBrace,
    /// `HIERARCHY` declares no joint.
    #[error("the hierarchy has no ROOT")]
    NoRoot,
    /// The hierarchy is not followed by `MOTION`.
    #[error("no MOTION section after the hierarchy")]
    MissingMotion,
    /// A frame line has the wrong number of values.
    #[error("frame {frame} has {got} values, expected {expected} (one per channel)")]
    FrameValues {
        /// 0-based frame index.
        frame: usize,
        /// Channels in the hierarchy.
        expected: usize,
        /// Values on the line.
        got: usize,
    },
    /// The number of frame lines differs from `Frames:`.
    #[error("Frames: says {declared} but the file has {found} frame lines")]
    FrameCount {
        /// `Frames:` value.
        declared: usize,
        /// Non-empty lines after `Frame Time`.
        found: usize,
    },
}

type Failure = (usize, Problem);

/// Tokens with their 1-based line numbers.
struct Lexer<'a> {
    lines: std::iter::Enumerate<std::str::Split<'a, char>>,
    line: usize,
    tokens: Option<SplitAsciiWhitespace<'a>>,
}

impl<'a> Lexer<'a> {
    fn new(text: &'a str) -> Self {
        Lexer {
            lines: text.split('\n').enumerate(),
            line: 0,
            tokens: None,
        }
    }

    fn next(&mut self) -> Option<(usize, &'a str)> {
        loop {
            if let Some(token) = self.tokens.as_mut().and_then(Iterator::next) {
                return Some((self.line, token));
            }
            let (index, line) = self.lines.next()?;
            self.line = index + 1;
            self.tokens = Some(line.split_ascii_whitespace());
        }
    }

    /// The next token, or an error naming what was expected.
    fn expect_any(&mut self, expected: &'static str) -> Result<(usize, &'a str), Failure> {
        self.next()
            .ok_or((self.line, Problem::UnexpectedEnd { expected }))
    }

    /// Consumes the next token, which must be `word`.
    fn expect(&mut self, word: &'static str) -> Result<usize, Failure> {
        let (line, token) = self.expect_any(word)?;
        if token == word {
            Ok(line)
        } else {
            Err((
                line,
                Problem::Expected {
                    expected: word,
                    found: excerpt(token),
                },
            ))
        }
    }

    /// The remaining tokens of the current line.
    fn rest_of_line(&mut self) -> Vec<&'a str> {
        self.tokens.take().map_or_else(Vec::new, Iterator::collect)
    }

    fn number(&mut self, expected: &'static str) -> Result<f64, Failure> {
        let (line, token) = self.expect_any(expected)?;
        number(token).map_err(|p| (line, p))
    }
}

fn number(token: &str) -> Result<f64, Problem> {
    match token.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(Problem::NonFinite {
            token: excerpt(token),
        }),
        Err(_) => Err(Problem::NotANumber {
            token: excerpt(token),
        }),
    }
}

fn channel(token: &str) -> Option<Channel> {
    Some(match token {
        "Xposition" => Channel::Xposition,
        "Yposition" => Channel::Yposition,
        "Zposition" => Channel::Zposition,
        "Xrotation" => Channel::Xrotation,
        "Yrotation" => Channel::Yrotation,
        "Zrotation" => Channel::Zrotation,
        _ => return None,
    })
}

/// A `{ … }` block being read.
struct Open {
    /// The joint, or for an End Site, the joint it belongs to.
    joint: usize,
    end_site: bool,
    brace_line: usize,
    offset: Option<DVec3>,
    channels_seen: bool,
}

impl Open {
    fn label(&self, joints: &[Joint]) -> String {
        let name = &joints[self.joint].name;
        if self.end_site {
            format!("End Site of {name}")
        } else {
            name.clone()
        }
    }
}

pub(super) fn parse(text: &str) -> Result<Mocap, Failure> {
    // A leading byte-order mark would glue itself to `HIERARCHY`.
    let text = crate::text::without_bom(text);
    let mut lex = Lexer::new(text);
    // Nothing of a file that is not BVH is quoted: it may be any file a path points at.
    let (line, first) = lex.expect_any("HIERARCHY")?;
    if first != "HIERARCHY" {
        return Err((line, Problem::NotBvh));
    }
    let joints = hierarchy(&mut lex)?;
    motion(&mut lex, joints, text.len())
}

/// Reads joints up to and including `MOTION`.
fn hierarchy(lex: &mut Lexer) -> Result<Vec<Joint>, Failure> {
    let mut joints: Vec<Joint> = Vec::new();
    let mut declared: HashMap<String, usize> = HashMap::new();
    let mut channel_count = 0;
    let mut stack: Vec<Open> = Vec::new();
    loop {
        let Some((line, token)) = lex.next() else {
            return Err(match stack.last() {
                Some(open) => unclosed(open, &joints),
                None => (lex.line, Problem::MissingMotion),
            });
        };
        let top = stack.last_mut();
        match (token, top) {
            ("MOTION", None) if joints.is_empty() => return Err((line, Problem::NoRoot)),
            ("MOTION", None) => return Ok(joints),
            ("MOTION", Some(open)) => return Err(unclosed(open, &joints)),
            ("ROOT", None) => {
                stack.push(open_joint(lex, line, None, &mut joints, &mut declared)?);
            }
            ("JOINT", Some(open)) if !open.end_site => {
                let parent = open.joint;
                stack.push(open_joint(
                    lex,
                    line,
                    Some(parent),
                    &mut joints,
                    &mut declared,
                )?);
            }
            ("End", Some(open)) if !open.end_site => {
                let joint = open.joint;
                lex.expect("Site")?;
                let brace_line = lex.expect("{")?;
                stack.push(Open {
                    joint,
                    end_site: true,
                    brace_line,
                    offset: None,
                    channels_seen: false,
                });
            }
            ("OFFSET", Some(open)) => read_offset(lex, line, open, &joints)?,
            ("CHANNELS", Some(open)) if !open.end_site => {
                read_channels(lex, line, open, &mut joints, &mut channel_count)?;
            }
            ("}", Some(_)) => {
                let open = stack.pop().unwrap_or_else(|| unreachable!("matched Some"));
                close(open, line, &mut joints)?;
            }
            ("}", None) => return Err((line, Problem::StrayBrace)),
            (found, top) => {
                let expected = match top {
                    None => "ROOT or MOTION",
                    Some(open) if open.end_site => "OFFSET or }",
                    Some(_) => "OFFSET, CHANNELS, JOINT, End Site or }",
                };
                return Err((
                    line,
                    Problem::Expected {
                        expected,
                        found: excerpt(found),
                    },
                ));
            }
        }
    }
}

/// The failure for a `{` still open where the hierarchy ends.
fn unclosed(open: &Open, joints: &[Joint]) -> Failure {
    (
        open.brace_line,
        Problem::UnclosedBrace {
            joint: open.label(joints),
            opened: open.brace_line,
        },
    )
}

/// Reads the three coordinates after `OFFSET` (on `line`) into the open block.
fn read_offset(
    lex: &mut Lexer,
    line: usize,
    open: &mut Open,
    joints: &[Joint],
) -> Result<(), Failure> {
    if open.offset.is_some() {
        return Err((
            line,
            Problem::Repeated {
                what: "OFFSET",
                joint: open.label(joints),
            },
        ));
    }
    let mut v = [0.0; 3];
    for c in &mut v {
        *c = lex.number("an OFFSET coordinate")?;
    }
    open.offset = Some(DVec3::from(v));
    Ok(())
}

/// Reads the count and names after `CHANNELS` (on `line`) into the open joint; its channels
/// start at `channel_count`, which grows by their number.
fn read_channels(
    lex: &mut Lexer,
    line: usize,
    open: &mut Open,
    joints: &mut [Joint],
    channel_count: &mut usize,
) -> Result<(), Failure> {
    let joint = &mut joints[open.joint];
    if open.channels_seen {
        return Err((
            line,
            Problem::Repeated {
                what: "CHANNELS",
                joint: joint.name.clone(),
            },
        ));
    }
    open.channels_seen = true;
    let (line, count) = lex.expect_any("a channel count")?;
    let count = match count.parse::<usize>() {
        Ok(n) if n <= 6 => n,
        _ => {
            return Err((
                line,
                Problem::BadChannelCount {
                    found: excerpt(count),
                },
            ));
        }
    };
    joint.first_channel = *channel_count;
    for _ in 0..count {
        let (line, name) = lex.expect_any("a channel name")?;
        let c = channel(name).ok_or_else(|| {
            (
                line,
                Problem::UnknownChannel {
                    name: excerpt(name),
                },
            )
        })?;
        if joint.channels.contains(&c) {
            return Err((
                line,
                Problem::RepeatedChannel {
                    joint: joint.name.clone(),
                    channel: c,
                },
            ));
        }
        joint.channels.push(c);
    }
    *channel_count += count;
    Ok(())
}

/// Closes a block at its `}` (on `line`): its offset becomes the joint's, or an End Site's.
fn close(open: Open, line: usize, joints: &mut [Joint]) -> Result<(), Failure> {
    let offset = open.offset.ok_or_else(|| {
        (
            line,
            Problem::MissingOffset {
                joint: open.label(joints),
            },
        )
    })?;
    let joint = &mut joints[open.joint];
    if open.end_site {
        joint.end_sites.push(offset);
    } else {
        joint.offset = offset;
    }
    Ok(())
}

/// Reads `name {` after `ROOT` or `JOINT` and adds the joint. The name is the rest of the line,
/// so names with spaces survive.
fn open_joint(
    lex: &mut Lexer,
    line: usize,
    parent: Option<usize>,
    joints: &mut Vec<Joint>,
    declared: &mut HashMap<String, usize>,
) -> Result<Open, Failure> {
    let name = lex.rest_of_line().join(" ");
    if name.is_empty() {
        return Err((
            line,
            Problem::Expected {
                expected: "a joint name on the same line",
                found: String::new(),
            },
        ));
    }
    if let Some(&first_line) = declared.get(&name) {
        return Err((line, Problem::DuplicateJoint { name, first_line }));
    }
    declared.insert(name.clone(), line);
    let brace_line = lex.expect("{")?;
    joints.push(Joint {
        name,
        parent,
        offset: DVec3::ZERO,
        channels: Vec::new(),
        first_channel: 0,
        end_sites: Vec::new(),
    });
    Ok(Open {
        joint: joints.len() - 1,
        end_site: false,
        brace_line,
        offset: None,
        channels_seen: false,
    })
}

/// Reads `Frames:`, `Frame Time:` and the frame lines after `MOTION`.
fn motion(lex: &mut Lexer, joints: Vec<Joint>, text_len: usize) -> Result<Mocap, Failure> {
    lex.expect("Frames:")?;
    let (line, token) = lex.expect_any("a frame count")?;
    let declared = token.parse::<usize>().map_err(|_| {
        (
            line,
            Problem::NotANumber {
                token: excerpt(token),
            },
        )
    })?;
    lex.expect("Frame")?;
    let line = lex.expect("Time:")?;
    let frame_time = lex.number("the frame time")?;
    // 1e-320 is positive, but its frame rate overflows to infinity and resampling to NaN.
    if frame_time <= 0.0 || !(1.0 / frame_time).is_finite() {
        return Err((line, Problem::BadFrameTime { value: frame_time }));
    }
    if let Some(&extra) = lex.rest_of_line().first() {
        return Err((
            lex.line,
            Problem::Expected {
                expected: "the end of the Frame Time line",
                found: excerpt(extra),
            },
        ));
    }
    let channel_count: usize = joints.iter().map(|j| j.channels.len()).sum();
    // Reserve no more than the text could hold (a value and its separator take at least two
    // bytes), whatever `Frames:` claims.
    let mut values = Vec::with_capacity(declared.saturating_mul(channel_count).min(text_len / 2));
    let mut found = 0;
    let mut first_extra_line = None;
    for (index, text) in lex.lines.by_ref() {
        let line = index + 1;
        let mut tokens = text.split_ascii_whitespace().peekable();
        if tokens.peek().is_none() {
            continue;
        }
        if found >= declared {
            first_extra_line.get_or_insert(line);
            found += 1;
            continue;
        }
        let mut got = 0;
        for token in tokens {
            got += 1;
            if got <= channel_count {
                values.push(number(token).map_err(|p| (line, p))?);
            }
        }
        if got != channel_count {
            return Err((
                line,
                Problem::FrameValues {
                    frame: found,
                    expected: channel_count,
                    got,
                },
            ));
        }
        found += 1;
        lex.line = line;
    }
    if found != declared {
        return Err((
            first_extra_line.unwrap_or(lex.line),
            Problem::FrameCount { declared, found },
        ));
    }
    Ok(Mocap {
        joints,
        frame_time,
        channel_count,
        frame_count: declared,
        values,
    })
}

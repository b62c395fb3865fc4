//! Where a run escaped dead ends: the stretches of rows driven by a walk, a
//! detour or the final return (`capp_core::escape`), for the summary, the
//! pictures and the planning benchmark.
//!
//! A row records the escape's state *after* its step, and that state drives
//! the next step. So a stretch whose rows are `first..=last` moved the arm
//! from row `first` (where the dead end was found: the escape "starts at its
//! step") to row `last + 1` (the row after a finished walk or detour is
//! `Descending` again; a return ends the run at `last`). Consecutive rows of
//! one attempt make one stretch; a new attempt starts a new one.
//!
//! The trajectory CSV's `escape` column ([`label`]) is read back by
//! [`parse_label`], so `capp render` on an output folder draws the same
//! stretches as `capp run --render`.

use capp_core::escape::{EscapeState, Side};

/// What an escape stretch does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Kind {
    /// The end effector sent round the blocking obstacle.
    Detour,
    /// A random walk in joint space away from the dead end.
    Walk,
    /// The attempts spent: back to the best configuration (the run then ends `Stalled`).
    Return,
    /// A search for a path, the arm holding still (`capp_core::escape::search`).
    Search,
    /// The walk along the path a search found.
    Path,
}

impl Kind {
    /// `detour`, `walk`, `return`, `search`, `path`.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Detour => "detour",
            Kind::Walk => "walk",
            Kind::Return => "return",
            Kind::Search => "search",
            Kind::Path => "path",
        }
    }
}

/// The stretch kind, attempt (1-based; 0 for the return) and side of an
/// escaping state; `None` while the law drives.
pub fn classify(state: EscapeState) -> Option<(Kind, u8, Option<Side>)> {
    match state {
        EscapeState::Descending { .. } => None,
        EscapeState::Detouring { attempt, side } => Some((Kind::Detour, attempt, Some(side))),
        EscapeState::Walking { attempt, side } => Some((Kind::Walk, attempt, side)),
        EscapeState::Returning => Some((Kind::Return, 0, None)),
        EscapeState::Searching { attempt, side } => Some((Kind::Search, attempt, side)),
        EscapeState::Following { attempt, side } => Some((Kind::Path, attempt, side)),
    }
}

/// One escape motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stretch {
    /// Detour, walk or return.
    pub kind: Kind,
    /// Attempt number for the waypoint (1-based; 0 for the return).
    pub attempt: u8,
    /// The side of the blocking obstacle taken (`None`: no obstacle blocked,
    /// or the return).
    pub side: Option<Side>,
    /// Index of the first row in this state (the dead end).
    pub first: usize,
    /// Index of the last row in this state.
    pub last: usize,
    /// Step number of row `first`: where the escape started.
    pub step: u32,
    /// Active waypoint (0-based) at row `first`.
    pub waypoint: u8,
}

impl Stretch {
    /// Index of the last row the stretch's motion reaches (`last + 1`, or
    /// `last` when it is the final row of `rows` rows).
    pub fn end(&self, rows: usize) -> usize {
        (self.last + 1).min(rows.saturating_sub(1))
    }
}

/// The stretches of a run given, per row in order, its step, waypoint and
/// escape state (`None`: not escaping, or not known).
pub fn stretches(rows: impl IntoIterator<Item = (u32, u8, Option<EscapeState>)>) -> Vec<Stretch> {
    let mut out: Vec<Stretch> = Vec::new();
    let mut open = false;
    for (i, (step, waypoint, state)) in rows.into_iter().enumerate() {
        let Some((kind, attempt, side)) = state.and_then(classify) else {
            open = false;
            continue;
        };
        match out.last_mut() {
            Some(s)
                if open
                    && s.kind == kind
                    && s.attempt == attempt
                    && s.waypoint == waypoint
                    && s.last + 1 == i =>
            {
                s.last = i;
            }
            _ => out.push(Stretch {
                kind,
                attempt,
                side,
                first: i,
                last: i,
                step,
                waypoint,
            }),
        }
        open = true;
    }
    out
}

/// The stretches of recorded plan rows (none for rows received from a board).
pub fn of_rows(rows: &[crate::plan::Row]) -> Vec<Stretch> {
    stretches(rows.iter().map(|r| (r.step, r.waypoint, r.escape)))
}

/// `+x`, `-z`, ...: a side of an obstacle in its own frame.
pub fn side_name(s: Side) -> String {
    format!(
        "{}{}",
        if s.positive { '+' } else { '-' },
        ['x', 'y', 'z'][(s.axis as usize).min(2)]
    )
}

/// What the `escape` column of the trajectory CSV says: empty while the law
/// drives, else `walk K`, `walk K obstacle O +z`, `detour K obstacle O -x`,
/// `search K [obstacle O +y]`, `path K [obstacle O +y]` (1-based attempt and
/// obstacle, the side of the obstacle in its own frame) or `return`.
pub fn label(state: EscapeState) -> String {
    let side = |s: Side| format!("obstacle {} {}", s.obstacle as u32 + 1, side_name(s));
    match state {
        EscapeState::Descending { .. } => String::new(),
        EscapeState::Walking {
            attempt,
            side: None,
        } => format!("walk {attempt}"),
        EscapeState::Walking {
            attempt,
            side: Some(s),
        } => format!("walk {attempt} {}", side(s)),
        EscapeState::Detouring { attempt, side: s } => format!("detour {attempt} {}", side(s)),
        EscapeState::Returning => "return".into(),
        EscapeState::Searching { attempt, side: s } => match s {
            Some(s) => format!("search {attempt} {}", side(s)),
            None => format!("search {attempt}"),
        },
        EscapeState::Following { attempt, side: s } => match s {
            Some(s) => format!("path {attempt} {}", side(s)),
            None => format!("path {attempt}"),
        },
    }
}

/// Reads a [`label`] back: `Ok(None)` for an empty cell (the law drives, or
/// not known: the attempts made so far are not in the column), an error
/// message for anything else it cannot read.
pub fn parse_label(text: &str) -> Result<Option<EscapeState>, String> {
    let words: Vec<&str> = text.split_whitespace().collect();
    let bad = || {
        format!("\"{text}\" is not an escape state (walk K [obstacle O +x], detour K obstacle O -y, search K [obstacle O +x], path K [obstacle O +x], return)")
    };
    let attempt = |w: &str| w.parse::<u8>().ok().filter(|&a| a > 0);
    let side = |o: &str, s: &str| -> Option<Side> {
        let obstacle = o.parse::<u32>().ok()?.checked_sub(1)?;
        let mut c = s.chars();
        let positive = match c.next()? {
            '+' => true,
            '-' => false,
            _ => return None,
        };
        let axis = match c.next()? {
            'x' => 0,
            'y' => 1,
            'z' => 2,
            _ => return None,
        };
        c.next().is_none().then_some(Side {
            obstacle: u8::try_from(obstacle).ok()?,
            axis,
            positive,
        })
    };
    match words.as_slice() {
        [] => Ok(None),
        ["return"] => Ok(Some(EscapeState::Returning)),
        ["walk", k] => Ok(Some(EscapeState::Walking {
            attempt: attempt(k).ok_or_else(bad)?,
            side: None,
        })),
        ["walk", k, "obstacle", o, s] => Ok(Some(EscapeState::Walking {
            attempt: attempt(k).ok_or_else(bad)?,
            side: Some(side(o, s).ok_or_else(bad)?),
        })),
        ["search", k] => Ok(Some(EscapeState::Searching {
            attempt: attempt(k).ok_or_else(bad)?,
            side: None,
        })),
        ["search", k, "obstacle", o, s] => Ok(Some(EscapeState::Searching {
            attempt: attempt(k).ok_or_else(bad)?,
            side: Some(side(o, s).ok_or_else(bad)?),
        })),
        ["path", k] => Ok(Some(EscapeState::Following {
            attempt: attempt(k).ok_or_else(bad)?,
            side: None,
        })),
        ["path", k, "obstacle", o, s] => Ok(Some(EscapeState::Following {
            attempt: attempt(k).ok_or_else(bad)?,
            side: Some(side(o, s).ok_or_else(bad)?),
        })),
        ["detour", k, "obstacle", o, s] => Ok(Some(EscapeState::Detouring {
            attempt: attempt(k).ok_or_else(bad)?,
            side: side(o, s).ok_or_else(bad)?,
        })),
        _ => Err(bad()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn side(obstacle: u8, axis: u8, positive: bool) -> Side {
        Side {
            obstacle,
            axis,
            positive,
        }
    }

    #[test]
    fn labels_read_back() {
        for state in [
            EscapeState::Returning,
            EscapeState::Walking {
                attempt: 3,
                side: None,
            },
            EscapeState::Walking {
                attempt: 12,
                side: Some(side(4, 2, true)),
            },
            EscapeState::Detouring {
                attempt: 1,
                side: side(0, 0, false),
            },
            EscapeState::Searching {
                attempt: 2,
                side: None,
            },
            EscapeState::Searching {
                attempt: 5,
                side: Some(side(1, 1, false)),
            },
            EscapeState::Following {
                attempt: 2,
                side: None,
            },
            EscapeState::Following {
                attempt: 7,
                side: Some(side(2, 0, true)),
            },
        ] {
            assert_eq!(parse_label(&label(state)), Ok(Some(state)), "{state:?}");
        }
        assert_eq!(parse_label(""), Ok(None));
        assert_eq!(
            label(EscapeState::Detouring {
                attempt: 2,
                side: side(0, 1, true)
            }),
            "detour 2 obstacle 1 +y"
        );
        for bad in [
            "walk",
            "walk 0",
            "walk x",
            "detour 1",
            "detour 1 obstacle 0 +x",
            "detour 1 obstacle 1 +w",
            "detour 1 obstacle 1 x",
            "returning",
            "search",
            "path 0",
            "search 1 obstacle 1",
        ] {
            assert!(parse_label(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn stretches_split_by_attempt_and_end_after_their_last_row() {
        let walk = |attempt| {
            Some(EscapeState::Walking {
                attempt,
                side: None,
            })
        };
        let law = Some(EscapeState::Descending { attempts: 1 });
        let rows = [
            law,
            walk(1),
            walk(1),
            law,
            walk(2),
            walk(3),
            None,
            Some(EscapeState::Returning),
        ];
        let s = stretches(rows.iter().enumerate().map(|(i, e)| (10 * i as u32, 0, *e)));
        let spans: Vec<(Kind, u8, usize, usize, u32)> = s
            .iter()
            .map(|s| (s.kind, s.attempt, s.first, s.last, s.step))
            .collect();
        assert_eq!(
            spans,
            [
                (Kind::Walk, 1, 1, 2, 10),
                (Kind::Walk, 2, 4, 4, 40),
                (Kind::Walk, 3, 5, 5, 50),
                (Kind::Return, 0, 7, 7, 70),
            ]
        );
        assert_eq!(s[0].end(rows.len()), 3);
        assert_eq!(s[3].end(rows.len()), 7);
    }
}

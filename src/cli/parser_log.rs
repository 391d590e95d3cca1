//! The SVG parser's own warnings (usvg and the crates under it log through the
//! `log` crate), kept off the terminal and folded into triwild's: a failure
//! prints exactly one line, a success at most one line for all of them, with
//! the file's name, and triwild's private element ids (given to id-less
//! shapes so their paths can be matched to the source) said as positions.

use std::sync::Mutex;
use tracing::field::{Field, Visit};
use tracing::{Event, Subscriber};
use tracing_subscriber::layer::{Context, Layer};

/// The parser's messages since the last [`take`].
static COLLECTED: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Whether an event comes from outside triwild (the parser and its crates).
pub(crate) fn is_foreign(target: &str) -> bool {
    !target.starts_with("triwild")
}

/// A layer that keeps the message of every foreign warning (or error) event.
pub(crate) struct Collect;

impl<S: Subscriber> Layer<S> for Collect {
    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        let meta = event.metadata();
        if !is_foreign(meta.target()) || *meta.level() > tracing::Level::WARN {
            return;
        }
        let mut visit = Message(String::new());
        event.record(&mut visit);
        if let Ok(mut all) = COLLECTED.lock() {
            all.push(visit.0);
        }
    }
}

struct Message(String);

impl Visit for Message {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            self.0 = format!("{value:?}");
        }
    }
    fn record_str(&mut self, field: &Field, value: &str) {
        if field.name() == "message" {
            self.0 = value.to_owned();
        }
    }
}

/// The messages collected since the last call, emptied.
pub(crate) fn take() -> Vec<String> {
    COLLECTED
        .lock()
        .map(|mut all| std::mem::take(&mut *all))
        .unwrap_or_default()
}

/// The parser's messages as one warning (`None` for none): how many, and the
/// first few distinct ones, with triwild's private ids said as positions.
pub(crate) fn folded(messages: &[String]) -> Option<String> {
    const SHOWN: usize = 3;
    if messages.is_empty() {
        return None;
    }
    let mut distinct: Vec<String> = Vec::new();
    for m in messages {
        let m = without_private_ids(m.trim().trim_end_matches('.'));
        if !distinct.contains(&m) {
            distinct.push(m);
        }
    }
    let more = if distinct.len() > SHOWN {
        format!("; and {} more", distinct.len() - SHOWN)
    } else {
        String::new()
    };
    distinct.truncate(SHOWN);
    Some(format!(
        "the SVG parser ignored what it could not read ({} warning(s)): {}{more}",
        messages.len(),
        distinct.join("; ")
    ))
}

/// `'triwild<k>-<n>'` (a private id) as "shape n + 1 without an id".
fn without_private_ids(m: &str) -> String {
    let mut out = String::with_capacity(m.len());
    let mut rest = m;
    while let Some(at) = rest.find("'triwild") {
        out.push_str(&rest[..at]);
        let tail = &rest[at + 1..];
        let end = tail.find('\'');
        let n = end.and_then(|e| {
            let id = &tail[..e];
            let (prefix, n) = id.rsplit_once('-')?;
            let k = prefix.strip_prefix("triwild")?;
            (k.bytes().all(|b| b.is_ascii_digit())).then_some(())?;
            n.parse::<u64>().ok()
        });
        match (n, end) {
            (Some(n), Some(e)) => {
                out.push_str(&format!("(shape {} without an id)", n + 1));
                rest = &tail[e + 1..];
            }
            _ => {
                out.push('\'');
                rest = tail;
            }
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn private_ids_are_said_as_positions_and_messages_fold() {
        assert_eq!(
            without_private_ids("Rect 'triwild0-1' has an invalid 'width' value. Skipped."),
            "Rect (shape 2 without an id) has an invalid 'width' value. Skipped."
        );
        assert_eq!(without_private_ids("x 'triwildy' z"), "x 'triwildy' z");
        let msgs: Vec<String> = ["a.", "a", "b", "c", "d"].map(String::from).to_vec();
        let f = folded(&msgs).expect("a line");
        assert!(f.contains("(5 warning(s)): a; b; c; and 1 more"), "{f}");
        assert!(!f.contains('\n'));
        assert_eq!(folded(&[]), None);
    }
}

//! `/phri/request` (`std_msgs/String`) into an [`HriRequest`]: the words of
//! `phri-hri request`, `KIND [PART]`: `begin` (or `start`), `follow PART`,
//! `end`, `stop`; PART `right_hand` or `left_hand`. `resume` is refused:
//! resuming a cell its dead-man stopped is for the operator at the cell.

use phri_ipc::{CollabPart, HriRequest, RequestKind, RequestSource, Zeroed, REQUEST_TEXT};

use crate::gate::shown;

/// Why a request text was refused. The words it holds are the received
/// ones cut and escaped ([`shown`]): an error is fit for a log line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RequestError {
    /// no word at all
    #[error("empty request")]
    Empty,
    /// the first word is not a request: the word, shown
    #[error("'{0}' is not a request (begin, start, follow PART, end, stop)")]
    Kind(String),
    /// the second word is not a part: the word, shown
    #[error("'{0}' is not a part (right_hand, left_hand)")]
    Part(String),
    /// `follow` without a part
    #[error("follow needs a part (right_hand, left_hand)")]
    PartMissing,
    /// `end` or `stop` with a part: the request's name
    #[error("{0} names no part")]
    PartNotTaken(&'static str),
    /// `resume`: the operator's alone, at the cell
    #[error("resume is the operator's, at the cell (phri-hri resume)")]
    Resume,
    /// a word after the part: the first such word, shown
    #[error("'{0}' after the request")]
    Trailing(String),
}

/// The request `text` asks, numbered `seq` and stamped `stamp_ns`
/// \[CLOCK_MONOTONIC\]; from whoever shows the part.
pub fn parse(text: &str, seq: u64, stamp_ns: u64) -> Result<HriRequest, RequestError> {
    let mut words = text.split_whitespace();
    let first = words
        .next()
        .ok_or(RequestError::Empty)?
        .to_ascii_lowercase();
    let kind = match first.as_str() {
        "start" => RequestKind::Begin,
        w => RequestKind::from_name(w).map_err(|_| RequestError::Kind(shown(w)))?,
    };
    if kind == RequestKind::Resume {
        return Err(RequestError::Resume);
    }
    let part = match words.next() {
        Some(p) => {
            let p = p.to_ascii_lowercase();
            CollabPart::from_name(&p).map_err(|_| RequestError::Part(shown(&p)))?
        }
        None => CollabPart::None,
    };
    if let Some(rest) = words.next() {
        return Err(RequestError::Trailing(shown(rest)));
    }
    match kind {
        RequestKind::Follow if part == CollabPart::None => return Err(RequestError::PartMissing),
        RequestKind::End | RequestKind::Stop if part != CollabPart::None => {
            return Err(RequestError::PartNotTaken(kind.name()))
        }
        _ => {}
    }
    let mut r = HriRequest::zeroed();
    r.seq = seq;
    r.stamp_ns = stamp_ns;
    r.source = RequestSource::Ros2 as u32;
    r.kind = kind as u32;
    r.part = part as u32;
    r.person = u32::MAX;
    r.confidence = 1.0;
    // the words as understood (a request is at most two short words)
    let words: Vec<&str> = text.split_whitespace().collect();
    let t = words.join(" ");
    let t = t.as_bytes();
    let n = t.len().min(REQUEST_TEXT - 1);
    r.text[..n].copy_from_slice(&t[..n]);
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_operators_words_are_requests() {
        let r = parse("follow left_hand", 7, 99).unwrap();
        assert_eq!(r.kind, RequestKind::Follow as u32);
        assert_eq!(r.part, CollabPart::LeftHand as u32);
        assert_eq!(
            (r.seq, r.stamp_ns, r.source),
            (7, 99, RequestSource::Ros2 as u32)
        );
        assert_eq!(&r.text[..16], b"follow left_hand");
        assert_eq!(
            parse(" Start ", 1, 1).unwrap().kind,
            RequestKind::Begin as u32
        );
        assert_eq!(parse("stop", 1, 1).unwrap().kind, RequestKind::Stop as u32);
        assert_eq!(
            parse("begin right_hand", 1, 1).unwrap().part,
            CollabPart::RightHand as u32
        );
    }

    #[test]
    fn anything_else_is_refused_with_its_reason() {
        assert_eq!(parse("  ", 1, 1).err(), Some(RequestError::Empty));
        assert_eq!(
            parse("dance", 1, 1).err(),
            Some(RequestError::Kind("dance".into()))
        );
        assert_eq!(parse("follow", 1, 1).err(), Some(RequestError::PartMissing));
        assert_eq!(
            parse("follow foot", 1, 1).err(),
            Some(RequestError::Part("foot".into()))
        );
        assert_eq!(
            parse("stop left_hand", 1, 1).err(),
            Some(RequestError::PartNotTaken("stop"))
        );
        assert_eq!(parse("resume", 1, 1).err(), Some(RequestError::Resume));
        assert_eq!(
            parse("end now please", 1, 1).err(),
            Some(RequestError::Part("now".into()))
        );
        assert_eq!(
            parse("follow left_hand now", 1, 1).err(),
            Some(RequestError::Trailing("now".into()))
        );
    }

    #[test]
    fn a_refused_word_is_cut_and_escaped_in_its_error() {
        let huge = format!("{}\u{1b}", "d".repeat(1 << 20));
        let e = parse(&huge, 1, 1).unwrap_err().to_string();
        assert!(e.len() < 200, "{} bytes", e.len());
        let e = parse("follow left\u{7}hand", 1, 1).unwrap_err().to_string();
        assert!(e.contains("left\\u{7}hand"), "{e}");
        assert!(!e.chars().any(char::is_control), "{e}");
    }

    #[test]
    fn the_text_passed_on_is_the_words_as_understood() {
        let r = parse("follow\n\tleft_hand\r\n", 1, 1).unwrap();
        assert_eq!(&r.text[..17], b"follow left_hand\0");
    }
}

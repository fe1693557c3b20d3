//! Line lexer shared by the g2o and TORO readers: whitespace-separated fields with their columns,
//! strict numbers and ids (FORMATS.md §1, §7).
//!
//! Numbers follow the syntax C++ `operator>>` accepts (`1`, `-0.5`, `+0`, `.5`, `5.`, `1e-7`,
//! `1E+06`), which is what g2o, TORO and GTSAM read; everything they cannot read back (`nan`,
//! `inf`, decimal commas, hex, `1e400`) is an error here, with a hint saying why.

use crate::error::ParseErrorKind;
use crate::graph::{MAX_VERTEX_ID, VertexId};
use nom::bytes::complete::{take_till1, take_while};
use nom::character::complete::digit1;
use nom::number::complete::recognize_float;
use nom::{IResult, Parser};

/// One whitespace-separated field of a line and its 1-based byte column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Field<'a> {
    pub text: &'a [u8],
    pub col: usize,
}

impl Field<'_> {
    pub fn lossy(&self) -> String {
        String::from_utf8_lossy(self.text).into_owned()
    }
}

/// C++ `isspace` in the "C" locale: what `>>` skips between fields.
fn is_space(c: u8) -> bool {
    matches!(c, b' ' | b'\t' | b'\r' | b'\n' | b'\x0b' | b'\x0c')
}

fn spaces(input: &[u8]) -> IResult<&[u8], &[u8]> {
    take_while(is_space).parse(input)
}

fn token(input: &[u8]) -> IResult<&[u8], &[u8]> {
    take_till1(is_space).parse(input)
}

/// Splits `line` into fields (clearing `out` first). Columns are 1-based byte offsets.
pub fn split_fields<'a>(line: &'a [u8], out: &mut Vec<Field<'a>>) {
    out.clear();
    let mut rest = line;
    loop {
        let after_space = match spaces(rest) {
            Ok((r, _)) => r,
            Err(_) => return,
        };
        match token(after_space) {
            Ok((r, text)) => {
                out.push(Field {
                    text,
                    col: line.len() - after_space.len() + 1,
                });
                rest = r;
            }
            // Only whitespace (or nothing) is left.
            Err(_) => return,
        }
    }
}

/// A finite f64 from a field, exactly rounded; anything C++ `>>` would not read back is an error.
pub fn parse_f64(field: &Field) -> Result<f64, ParseErrorKind> {
    let text = field.text;
    let recognized = recognize_float::<&[u8], nom::error::Error<&[u8]>>(text);
    if !matches!(recognized, Ok((&[], _))) {
        return Err(not_a_number(field));
    }
    // `recognize_float` only matches ASCII, so this cannot fail.
    let s = std::str::from_utf8(text).map_err(|_| not_a_number(field))?;
    let v: f64 = s.parse().map_err(|_| not_a_number(field))?;
    if v.is_infinite() {
        return Err(ParseErrorKind::OutOfRange {
            token: field.lossy(),
            what: "overflows to infinity",
        });
    }
    if v == 0.0 && mantissa_has_nonzero_digit(text) {
        return Err(ParseErrorKind::OutOfRange {
            token: field.lossy(),
            what: "underflows to zero",
        });
    }
    Ok(v)
}

fn mantissa_has_nonzero_digit(text: &[u8]) -> bool {
    text.iter()
        .take_while(|&&c| c != b'e' && c != b'E')
        .any(|&c| (b'1'..=b'9').contains(&c))
}

fn not_a_number(field: &Field) -> ParseErrorKind {
    let lower = field.lossy().to_ascii_lowercase();
    let unsigned = lower.trim_start_matches(['+', '-']);
    let hint = if unsigned.starts_with("nan") || unsigned.starts_with("inf") {
        " (non-finite values are not allowed: g2o and GTSAM cannot read them back)"
    } else if unsigned.starts_with("0x") {
        " (hexadecimal numbers are not accepted)"
    } else if lower.contains(',') {
        " (a decimal comma? numbers use '.' as the decimal separator)"
    } else {
        ""
    };
    ParseErrorKind::NotANumber {
        token: field.lossy(),
        hint,
    }
}

/// A vertex id: a decimal integer in `0..=2^31 - 1` (g2o's `int`, FORMATS.md §2.3).
pub fn parse_id(field: &Field) -> Result<VertexId, ParseErrorKind> {
    let text = field.text;
    let invalid = |reason| ParseErrorKind::InvalidId {
        token: field.lossy(),
        reason,
    };
    if let Ok((rest, digits)) = digit1::<&[u8], nom::error::Error<&[u8]>>(text) {
        if rest.is_empty() {
            // Leading zeros are fine; the value decides the range.
            let value = digits.iter().try_fold(0u64, |acc, &d| {
                let next = acc * 10 + u64::from(d - b'0');
                (next <= u64::from(MAX_VERTEX_ID)).then_some(next)
            });
            return value.map(|v| v as VertexId).ok_or_else(|| {
                invalid(
                    "ids must be at most 2^31 - 1 = 2147483647 (g2o stores them as a 32-bit int)",
                )
            });
        }
        if rest[0] == b'.' || rest[0] == b'e' || rest[0] == b'E' {
            return Err(invalid("ids are integers"));
        }
    }
    if text.first() == Some(&b'-') {
        return Err(invalid("ids cannot be negative"));
    }
    Err(invalid("ids are decimal integers"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields(line: &str) -> Vec<(String, usize)> {
        let mut out = Vec::new();
        split_fields(line.as_bytes(), &mut out);
        out.iter().map(|f| (f.lossy(), f.col)).collect()
    }

    fn num(s: &str) -> Result<f64, ParseErrorKind> {
        parse_f64(&Field {
            text: s.as_bytes(),
            col: 1,
        })
    }

    fn id(s: &str) -> Result<VertexId, ParseErrorKind> {
        parse_id(&Field {
            text: s.as_bytes(),
            col: 1,
        })
    }

    #[test]
    fn splits_on_runs_of_any_whitespace() {
        assert_eq!(
            fields("  A\tb  c \r"),
            vec![("A".into(), 3), ("b".into(), 5), ("c".into(), 8)]
        );
        assert!(fields(" \t \r").is_empty());
    }

    #[test]
    fn numbers_cpp_accepts() {
        for (s, v) in [
            ("1", 1.0),
            ("-0.5", -0.5),
            ("+0", 0.0),
            (".5", 0.5),
            ("5.", 5.0),
            ("1e-7", 1e-7),
            ("1E+06", 1e6),
            ("6.95335e-310", 6.95335e-310),
        ] {
            assert_eq!(num(s), Ok(v), "{s}");
        }
        // The sign of zero is kept.
        assert!(num("-0").unwrap().is_sign_negative());
        assert!(num("-0.000000").unwrap().is_sign_negative());
    }

    #[test]
    fn numbers_rejected_with_reasons() {
        for s in ["nan", "NaN", "inf", "-inf", "Infinity"] {
            let e = num(s).unwrap_err().to_string();
            assert!(e.contains("non-finite"), "{s}: {e}");
        }
        assert!(
            num("0,5")
                .unwrap_err()
                .to_string()
                .contains("decimal comma")
        );
        assert!(num("0x10").unwrap_err().to_string().contains("hexadecimal"));
        assert!(num("1e400").unwrap_err().to_string().contains("overflows"));
        assert!(
            num("1e-400")
                .unwrap_err()
                .to_string()
                .contains("underflows")
        );
        for s in ["abc", "1.2.3", "1e", "--1", "1-"] {
            assert!(
                matches!(num(s), Err(ParseErrorKind::NotANumber { .. })),
                "{s}"
            );
        }
        // 0e-400 is a zero, not an underflow.
        assert_eq!(num("0e-400"), Ok(0.0));
    }

    #[test]
    fn ids() {
        assert_eq!(id("0"), Ok(0));
        assert_eq!(id("2147483647"), Ok(2147483647));
        assert_eq!(id("007"), Ok(7));
        for (s, why) in [
            ("2147483648", "at most"),
            ("99999999999999999999999", "at most"),
            ("-1", "negative"),
            ("1.5", "integers"),
            ("1.0", "integers"),
            ("1e3", "integers"),
            ("x1", "decimal"),
        ] {
            let e = id(s).unwrap_err().to_string();
            assert!(e.contains(why), "{s}: {e}");
        }
    }
}

//! Line lexer shared by the g2o and TORO readers: whitespace-separated fields with their columns,
//! strict numbers and ids (docs/formats.md §1, §7.1).
//!
//! Numbers follow the syntax C++ `operator>>` accepts (`1`, `-0.5`, `+0`, `.5`, `5.`, `1e-7`,
//! `1E+06`), which is what g2o, TORO and GTSAM read; everything they cannot read back (`nan`,
//! `inf`, decimal commas, hex, `1e400`) is an error here, with a hint saying why.
//!
//! Speed: the files are millions of short decimal numbers, and reading them at least ten times
//! faster than GTSAM's `readG2o` is a goal. So the common case takes a hand-written path (a byte
//! loop for the fields, Clinger's exact fast path for numbers with at most 19 digits and a small
//! decimal exponent, a digit loop for ids); everything else (long mantissas, large exponents,
//! subnormals, and every malformed token) goes through the nom grammar and the standard library's
//! correctly rounded parser, which also produce the error messages. Both paths give the same,
//! correctly rounded value.

use crate::error::ParseErrorKind;
use crate::graph::{MAX_VERTEX_ID, VertexId};
use nom::character::complete::digit1;
use nom::number::complete::recognize_float;

/// One whitespace-separated field of a line and its 1-based byte column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Field<'a> {
    pub text: &'a [u8],
    pub col: usize,
}

impl Field<'_> {
    /// The field as shown in messages: invalid UTF-8 as U+FFFD, control characters escaped
    /// (`\u{0}`, `\u{1b}`: a message never moves the terminal's cursor or rings its bell), and
    /// at most [`SHOWN_CHARS`] characters (a long token ends in `...`).
    pub fn lossy(&self) -> String {
        let mut out = String::new();
        for (k, c) in String::from_utf8_lossy(self.text).chars().enumerate() {
            if k == SHOWN_CHARS {
                out.push_str("...");
                break;
            }
            if c.is_control() {
                out.extend(c.escape_default());
            } else {
                out.push(c);
            }
        }
        out
    }
}

/// Longest token shown in full in a message.
pub const SHOWN_CHARS: usize = 64;

/// C++ `isspace` in the "C" locale: what `>>` skips between fields.
fn is_space(c: u8) -> bool {
    matches!(c, b' ' | b'\t' | b'\r' | b'\n' | b'\x0b' | b'\x0c')
}

/// Splits `line` into fields (clearing `out` first). Columns are 1-based byte offsets.
pub fn split_fields<'a>(line: &'a [u8], out: &mut Vec<Field<'a>>) {
    out.clear();
    let mut k = 0;
    while k < line.len() {
        if is_space(line[k]) {
            k += 1;
            continue;
        }
        let start = k;
        while k < line.len() && !is_space(line[k]) {
            k += 1;
        }
        out.push(Field {
            text: &line[start..k],
            col: start + 1,
        });
    }
}

/// Exact powers of ten representable in an f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Skips whitespace at the start of `s`.
pub fn skip_space(s: &mut &[u8]) {
    while let [c, rest @ ..] = *s {
        if !is_space(*c) {
            return;
        }
        *s = rest;
    }
}

/// Clinger's fast path: a decimal `[+-]digits[.digits][(e|E)[+-]digits]` whose significand has
/// at most 19 digits, is below 2^53, and whose decimal exponent is within ±22 is a product or
/// quotient of two exactly representable numbers, so one IEEE operation rounds it correctly.
///
/// Scans one such token at the start of `s` (which must end at whitespace or at the end of `s`)
/// and advances `s` past it; `None`, with `s` unchanged, for anything else (the caller takes the
/// general path).
pub fn scan_f64(s: &mut &[u8]) -> Option<f64> {
    let text = *s;
    let mut k = 0;
    let negative = match text.first() {
        Some(b'-') => {
            k = 1;
            true
        }
        Some(b'+') => {
            k = 1;
            false
        }
        _ => false,
    };
    let mut mantissa: u64 = 0;
    let int_start = k;
    while let Some(&c @ b'0'..=b'9') = text.get(k) {
        mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(c - b'0'));
        k += 1;
    }
    let mut digits = k - int_start;
    let mut scale: i32 = 0;
    if text.get(k) == Some(&b'.') {
        k += 1;
        let frac_start = k;
        while let Some(&c @ b'0'..=b'9') = text.get(k) {
            mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(c - b'0'));
            k += 1;
        }
        digits += k - frac_start;
        scale = -((k - frac_start) as i32);
    }
    // At most 19 digits (leading zeros included) cannot overflow a u64.
    if digits == 0 || digits > 19 {
        return None;
    }
    if let Some(b'e' | b'E') = text.get(k) {
        k += 1;
        let exp_negative = match text.get(k) {
            Some(b'-') => {
                k += 1;
                true
            }
            Some(b'+') => {
                k += 1;
                false
            }
            _ => false,
        };
        let exp_start = k;
        let mut e: i32 = 0;
        while let Some(&c @ b'0'..=b'9') = text.get(k) {
            if k - exp_start == 4 {
                return None;
            }
            e = e * 10 + i32::from(c - b'0');
            k += 1;
        }
        if k == exp_start {
            return None;
        }
        scale += if exp_negative { -e } else { e };
    }
    if text.get(k).is_some_and(|&c| !is_space(c)) {
        return None;
    }
    let value = if mantissa == 0 {
        0.0
    } else if mantissa > 1 << 53 || !(-22..=22).contains(&scale) {
        return None;
    } else if scale >= 0 {
        mantissa as f64 * POW10[scale as usize]
    } else {
        mantissa as f64 / POW10[(-scale) as usize]
    };
    *s = &text[k..];
    Some(if negative { -value } else { value })
}

/// [`scan_f64`] for each of `out`'s values in turn, each after whitespace; false (with `s` at
/// the value that failed) as soon as one is not on the fast path.
pub fn scan_f64s(s: &mut &[u8], out: &mut [f64]) -> bool {
    for x in out {
        skip_space(s);
        match scan_f64(s) {
            Some(value) => *x = value,
            None => return false,
        }
    }
    true
}

/// Scans a vertex id of up to 9 digits (always below 2^31) ending at whitespace or the end of
/// `s`, and advances `s` past it; `None`, with `s` unchanged, for anything else.
pub fn scan_id(s: &mut &[u8]) -> Option<VertexId> {
    let text = *s;
    let n = text.iter().take_while(|c| c.is_ascii_digit()).count();
    if n == 0 || n > 9 || text.get(n).is_some_and(|&c| !is_space(c)) {
        return None;
    }
    *s = &text[n..];
    Some(
        text[..n]
            .iter()
            .fold(0, |acc, &d| acc * 10 + VertexId::from(d - b'0')),
    )
}

/// [`scan_f64`] on a whole field.
fn fast_f64(text: &[u8]) -> Option<f64> {
    let mut rest = text;
    scan_f64(&mut rest).filter(|_| rest.is_empty())
}

/// A finite f64 from a field, exactly rounded; anything C++ `>>` would not read back is an error.
pub fn parse_f64(field: &Field) -> Result<f64, ParseErrorKind> {
    match fast_f64(field.text) {
        Some(v) => Ok(v),
        None => parse_f64_general(field),
    }
}

/// The general path: nom's float grammar, then the standard library's correctly rounded parse.
fn parse_f64_general(field: &Field) -> Result<f64, ParseErrorKind> {
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

/// A vertex id: a decimal integer in `0..=2^31 - 1` (g2o's `int`, docs/formats.md §2.3).
pub fn parse_id(field: &Field) -> Result<VertexId, ParseErrorKind> {
    let text = field.text;
    let mut rest = text;
    if let Some(id) = scan_id(&mut rest).filter(|_| rest.is_empty()) {
        return Ok(id);
    }
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
    fn fast_path_agrees_with_the_standard_parser() {
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut fast = 0;
        for _ in 0..200_000 {
            let r = next();
            // Decimals shaped like the data sets': a few integer digits, up to 17 fraction
            // digits, sometimes an exponent, sometimes a sign.
            let int = r % 100_000;
            let frac_digits = (next() % 18) as usize;
            let frac = next() % 10u64.pow(frac_digits.min(18) as u32).max(1);
            let mut s = format!("{}{int}", if r & 1 << 40 != 0 { "-" } else { "" });
            if frac_digits > 0 {
                s += &format!(".{frac:0frac_digits$}");
            }
            if r & 1 << 41 != 0 {
                s += &format!("e{}", (next() % 60) as i64 - 30);
            }
            let f = Field {
                text: s.as_bytes(),
                col: 1,
            };
            let want: f64 = s.parse().unwrap();
            assert_eq!(parse_f64(&f).unwrap().to_bits(), want.to_bits(), "{s}");
            fast += usize::from(fast_f64(s.as_bytes()).is_some());
        }
        // The fast path must actually be taken most of the time.
        assert!(fast > 100_000, "{fast}");
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

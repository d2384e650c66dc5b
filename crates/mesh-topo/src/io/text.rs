//! Byte-level helpers shared by the text readers: lines, tokens, numbers.

use super::{IoError, Location};

/// Lines of a byte buffer with 1-based numbers. A final line without `\n` counts; the
/// `\n` is not part of the line (a `\r` before it is, and is whitespace to the tokenizer).
pub(crate) struct Lines<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, pos: 0, line: 0 }
    }

    /// The lines of `bytes`, numbered from `lines_before + 1`.
    pub(crate) fn starting_after(bytes: &'a [u8], lines_before: usize) -> Self {
        Self { bytes, pos: 0, line: lines_before }
    }

    /// Number of the last line returned (0 before the first), i.e. the line count so far.
    pub(crate) fn line(&self) -> usize {
        self.line
    }

    /// Byte offset of the start of the next line.
    pub(crate) fn offset(&self) -> usize {
        self.pos
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.bytes.len() {
            return None;
        }
        let rest = &self.bytes[self.pos..];
        let (line, advance) = match memchr::memchr(b'\n', rest) {
            Some(end) => (&rest[..end], end + 1),
            None => (rest, rest.len()),
        };
        self.pos += advance;
        self.line += 1;
        Some((self.line, line))
    }
}

/// `bytes` cut into `count` pieces of about equal size (at least one; some may be
/// empty), each but the last ending with a line end, for reading in parallel.
pub(crate) fn cut_at_line_ends(bytes: &[u8], count: usize) -> Vec<&[u8]> {
    let mut cuts = vec![0];
    let mut previous = 0;
    for k in 1..count {
        let target = (bytes.len() * k / count).max(previous);
        previous = memchr::memchr(b'\n', &bytes[target..]).map_or(bytes.len(), |i| target + i + 1);
        cuts.push(previous);
    }
    cuts.push(bytes.len());
    cuts.windows(2).map(|w| &bytes[w[0]..w[1]]).collect()
}

/// The part of a line before a `#` comment.
#[inline]
pub(crate) fn strip_comment(line: &[u8]) -> &[u8] {
    match memchr::memchr(b'#', line) {
        Some(hash) => &line[..hash],
        None => line,
    }
}

#[inline]
pub(crate) fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c)
}

/// Whitespace-separated tokens of a line.
#[inline]
pub(crate) fn tokens(line: &[u8]) -> Tokens<'_> {
    Tokens { rest: line }
}

/// Iterator over whitespace-separated tokens.
#[derive(Clone)]
pub(crate) struct Tokens<'a> {
    rest: &'a [u8],
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    #[inline]
    fn next(&mut self) -> Option<&'a [u8]> {
        let start = self.rest.iter().position(|&b| !is_space(b))?;
        let rest = &self.rest[start..];
        let end = rest.iter().position(|&b| is_space(b)).unwrap_or(rest.len());
        self.rest = &rest[end..];
        Some(&rest[..end])
    }
}

/// Trailing whitespace removed.
#[inline]
pub(crate) fn trim_end(line: &[u8]) -> &[u8] {
    let end = line.iter().rposition(|&b| !is_space(b)).map_or(0, |i| i + 1);
    &line[..end]
}

/// A decimal floating-point number (Rust's grammar: `1`, `-1.5`, `.5`, `1e-3`, `inf`,
/// `NaN`...). Non-finite values parse; callers reject them where they matter. The value
/// is the standard library's, bit for bit: most coordinates in mesh files take the
/// exact shortcut of [`parse_short_decimal`], the others `f64::from_str`.
#[inline]
pub(crate) fn parse_f64(token: &[u8]) -> Option<f64> {
    parse_short_decimal(token).or_else(|| std::str::from_utf8(token).ok()?.parse().ok())
}

/// The powers of ten that are exact `f64` values.
const EXACT_POWERS_OF_TEN: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20,
    1e21, 1e22,
];

/// The longest token [`parse_short_decimal`] reads: a sign, 16 digits and a point fit.
const SHORT_DECIMAL_MAX_LEN: usize = 18;

/// Clinger's fast path: a token `[sign] digits [. digits] [(e|E) [sign] digits]` (at
/// least one digit before the exponent) whose digits, the point removed, make an integer
/// `m <= 2^53`, and whose value is `m * 10^k` with `|k| <= 22`. Then `m` and `10^|k|` are
/// exact `f64` values and one multiplication or division rounds their exact product or
/// quotient correctly: the standard library's result. `None` for anything else (other
/// forms, more digits, larger exponents, invalid tokens), left to `f64::from_str`.
#[inline]
fn parse_short_decimal(token: &[u8]) -> Option<f64> {
    // Longer tokens (the 17 significant digits of a shortest round-trip, say) rarely
    // qualify: they go to the standard library at once, not after a scan.
    if token.len() > SHORT_DECIMAL_MAX_LEN {
        return None;
    }
    let (negative, mut rest) = match token.first()? {
        b'-' => (true, &token[1..]),
        b'+' => (false, &token[1..]),
        _ => (false, token),
    };
    // At most 18 digits: no overflow; `m <= 2^53` is checked after.
    let (mut mantissa, mut digits, mut fraction_digits) = (0u64, 0u32, 0i64);
    let mut after_point = false;
    while let Some((&b, tail)) = rest.split_first() {
        match b {
            b'0'..=b'9' => {
                mantissa = mantissa * 10 + u64::from(b - b'0');
                digits += 1;
                fraction_digits += i64::from(after_point);
            }
            b'.' if !after_point => after_point = true,
            _ => break,
        }
        rest = tail;
    }
    if digits == 0 || mantissa > 1 << 53 {
        return None;
    }
    // The exponent, if any, is the rest of the token: a signed integer of at most 16
    // characters (no overflow).
    let exponent = match rest.split_first() {
        None => 0,
        Some((&(b'e' | b'E'), tail)) => parse_i64(tail)?,
        Some(_) => return None,
    };
    let power = exponent - fraction_digits;
    let value = mantissa as f64;
    let value = match power {
        0..=22 => value * EXACT_POWERS_OF_TEN[power as usize],
        -22..=-1 => value / EXACT_POWERS_OF_TEN[(-power) as usize],
        _ if mantissa == 0 => 0.0,
        _ => return None,
    };
    Some(if negative { -value } else { value })
}

/// A decimal integer with an optional sign, without overflow.
#[inline]
pub(crate) fn parse_i64(token: &[u8]) -> Option<i64> {
    let (negative, digits) = match token.first()? {
        b'-' => (true, &token[1..]),
        b'+' => (false, &token[1..]),
        _ => (false, token),
    };
    if digits.is_empty() {
        return None;
    }
    if digits.len() <= 18 {
        // Below 10^18 no sum can overflow: the plain loop (indices and counts take this
        // path; the checked one below is for the longest tokens).
        let mut value = 0i64;
        for &b in digits {
            let digit = b.wrapping_sub(b'0');
            if digit > 9 {
                return None;
            }
            value = value * 10 + digit as i64;
        }
        return Some(if negative { -value } else { value });
    }
    let mut value: i64 = 0;
    for &b in digits {
        let digit = b.wrapping_sub(b'0');
        if digit > 9 {
            return None;
        }
        // Accumulate negatively so that i64::MIN parses.
        value = value.checked_mul(10)?.checked_sub(digit as i64)?;
    }
    if negative { Some(value) } else { value.checked_neg() }
}

/// A token for an error message: invalid UTF-8 replaced, long tokens shortened.
pub(crate) fn show_token(token: &[u8]) -> String {
    const MAX: usize = 40;
    let text = String::from_utf8_lossy(token);
    if text.chars().count() > MAX {
        let mut short: String = text.chars().take(MAX).collect();
        short.push('…');
        short
    } else {
        text.into_owned()
    }
}

pub(crate) fn invalid_number(line: usize, token: &[u8], expected: &'static str) -> IoError {
    IoError::InvalidNumber { at: Location::Line(line), token: show_token(token), expected }
}

/// Parses a coordinate token: a finite-or-not number (finiteness is checked per vertex).
#[inline]
pub(crate) fn coordinate(line: usize, token: &[u8]) -> Result<f64, IoError> {
    parse_f64(token).ok_or_else(|| invalid_number(line, token, "a number"))
}

/// Fails with [`IoError::NonFiniteCoordinate`] if a coordinate is NaN or infinite.
#[inline]
pub(crate) fn check_finite(at: Location, vertex: usize, p: [f64; 3]) -> Result<(), IoError> {
    match p.iter().find(|x| !x.is_finite()) {
        Some(&value) => Err(IoError::NonFiniteCoordinate { at, vertex, value }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_number_from_one_and_keep_a_final_unterminated_line() {
        let lines: Vec<(usize, &[u8])> = Lines::new(b"a\r\nb\n\nc").collect();
        assert_eq!(lines, vec![(1, &b"a\r"[..]), (2, b"b"), (3, b""), (4, b"c")]);
        assert_eq!(Lines::new(b"").count(), 0);
        assert_eq!(Lines::new(b"x\n").count(), 1);
    }

    #[test]
    fn tokens_split_on_any_ascii_whitespace() {
        let t: Vec<&[u8]> = tokens(b" \tv  1.5\r").collect();
        assert_eq!(t, vec![&b"v"[..], b"1.5"]);
        assert_eq!(tokens(b"   ").count(), 0);
    }

    #[test]
    fn integers_parse_exactly_and_reject_overflow() {
        assert_eq!(parse_i64(b"-9223372036854775808"), Some(i64::MIN));
        assert_eq!(parse_i64(b"9223372036854775807"), Some(i64::MAX));
        assert_eq!(parse_i64(b"9223372036854775808"), None);
        assert_eq!(parse_i64(b"+12"), Some(12));
        for bad in [&b""[..], b"-", b"1.0", b"1e3", b"x", b"--1"] {
            assert_eq!(parse_i64(bad), None, "{bad:?}");
        }
    }

    proptest::proptest! {
        /// The grammar and the range of `i64::from_str`, digit counts on both sides of
        /// the fast path's limit included.
        #[test]
        fn integers_parse_as_the_standard_library_does(token in "[-+]?[0-9]{0,21}|[-+0-9a ]{0,6}") {
            let expected = token.parse::<i64>().ok();
            proptest::prop_assert_eq!(parse_i64(token.as_bytes()), expected);
        }
    }

    #[test]
    fn floats_follow_rust_grammar() {
        assert_eq!(parse_f64(b"-1.5e-3"), Some(-1.5e-3));
        assert_eq!(parse_f64(b".5"), Some(0.5));
        assert!(parse_f64(b"nan").unwrap().is_nan());
        assert_eq!(parse_f64(b"1,5"), None);
        assert_eq!(parse_f64(b"\xff"), None);
    }

    proptest::proptest! {
        /// Decimal tokens of every shape (digit counts on both sides of the shortcut's
        /// limits, points, exponents, signs, stray characters) parse to the standard
        /// library's value, bit for bit, or fail where it fails.
        #[test]
        fn floats_parse_as_the_standard_library_does(
            token in "[-+]?[0-9]{0,20}(\\.[0-9]{0,20})?([eE][-+]?[0-9]{0,5})?|[-+0-9.eE]{0,8}|[-+0-9.eEa-z_ ]{0,10}",
        ) {
            let expected = token.parse::<f64>().ok().map(f64::to_bits);
            proptest::prop_assert_eq!(parse_f64(token.as_bytes()).map(f64::to_bits), expected);
        }
    }

    #[test]
    fn the_shortcut_takes_the_usual_coordinates_and_leaves_the_rest() {
        for token in
            ["-0.338493", "0.120414", "1e-3", "-0", "0.0e-999", "12345678.5e+2", "-9007199254740992.", "1e00001"]
        {
            let expected = token.parse::<f64>().unwrap().to_bits();
            assert_eq!(parse_short_decimal(token.as_bytes()).map(f64::to_bits), Some(expected), "{token}");
        }
        // 2^53 + 1, a 23rd power of ten, a huge exponent, 19 characters, no digits, an
        // exponent without digits, words.
        let others =
            ["9007199254740993", "1e23", "1e-23", "1e99999", "0.00000000000000001", ".", "-.e1", "1e+", "inf", "NaN"];
        for token in others {
            assert_eq!(parse_short_decimal(token.as_bytes()), None, "{token}");
        }
    }

    #[test]
    fn long_tokens_are_shortened_in_messages() {
        let long = vec![b'x'; 100];
        assert_eq!(show_token(&long).chars().count(), 41);
        assert_eq!(show_token(b"ab\xffc"), "ab\u{fffd}c");
    }
}

//! Numbers as text for messages and tables: significant digits without
//! 300-digit decimals and without `-0`. The runtime's error messages need
//! them, so they live here; the report layer's tables re-export them.

/// Remove the sign of a formatted number whose digits are all zero
/// (`"-0.000"` -> `"0.000"`, `"+0.000"` stays unsigned-zero as `"+0.000"`
/// only when `plus` formatting was asked for).
fn drop_negative_zero(s: String) -> String {
    let digits_zero = s
        .chars()
        .take_while(|c| *c != 'e' && *c != 'E')
        .all(|c| matches!(c, '-' | '+' | '0' | '.'));
    if digits_zero && s.starts_with('-') {
        s[1..].to_string()
    } else {
        s
    }
}

/// `x` with `digits` significant digits: plain decimals for `1e-4 <= |x| <
/// 1e12`, scientific notation otherwise (so `1e-300` prints as
/// `1.00000e-300`, not with 300 digits); `0` and `-0` print as `0`.
///
/// ```
/// use bikedyn_runtime::number_text::format_significant;
/// assert_eq!(format_significant(80.81721999999998, 6), "80.8172");
/// assert_eq!(format_significant(-0.0, 6), "0");
/// assert_eq!(format_significant(1e-300, 3), "1.00e-300");
/// ```
pub fn format_significant(x: f64, digits: usize) -> String {
    let digits = digits.max(1);
    if x == 0.0 {
        return "0".to_string();
    }
    if !x.is_finite() {
        return x.to_string();
    }
    let e = x.abs().log10().floor() as i32;
    if !(-4..12).contains(&e) {
        return drop_negative_zero(format!("{:.*e}", digits - 1, x));
    }
    let decimals = (digits as i32 - 1 - e).max(0) as usize;
    drop_negative_zero(format!("{x:.decimals$}"))
}

/// `x` with a fixed number of decimals, and a `+` sign when `plus`; a value
/// that rounds to zero prints without a minus sign.
pub fn format_fixed(x: f64, decimals: usize, plus: bool) -> String {
    let s = if plus {
        format!("{x:+.decimals$}")
    } else {
        format!("{x:.decimals$}")
    };
    let s = drop_negative_zero(s);
    if plus && !s.starts_with(['+', '-']) {
        format!("+{s}")
    } else {
        s
    }
}

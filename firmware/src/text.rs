//! A line of text built without `core::fmt`: the QEMU image's semihosting
//! prints (integers, hexadecimal, fixed point and scientific notation),
//! written so that nothing here can panic (every store is a `get_mut`,
//! every division by a constant or checked) and no formatting machinery with its
//! indirect calls and panic paths is linked in.
//!
//! What it prints matches `core::fmt` for the forms used (`{}` of integers
//! and `&str`, `{:<N}`, `{:08x}`, `{:.Ne}`), except that the last digit of
//! `{:.Ne}` is rounded from an f64 computation (core rounds the exact
//! decimal expansion: the two can differ on a tie) and [`Line::exp`] (for
//! `{:e}`) prints nine significant digits without trailing zeros rather
//! than the shortest round-trip form (both say `0e0` for zero).

/// Bytes a line holds; what does not fit is dropped.
pub const LINE_CAPACITY: usize = 384;

/// A line being built.
pub struct Line {
    buf: [u8; LINE_CAPACITY],
    len: usize,
}

impl Default for Line {
    fn default() -> Self {
        Self::new()
    }
}

impl Line {
    /// An empty line.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            buf: [0; LINE_CAPACITY],
            len: 0,
        }
    }

    /// The text so far.
    #[must_use]
    pub fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    fn byte(&mut self, b: u8) {
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = b;
            self.len += 1;
        }
    }

    /// Appends `s`.
    pub fn str(&mut self, s: &str) -> &mut Self {
        for &b in s.as_bytes() {
            self.byte(b);
        }
        self
    }

    /// Appends `s` padded with spaces to `width` characters (`{:<width}`).
    pub fn str_padded(&mut self, s: &str, width: usize) -> &mut Self {
        self.str(s);
        for _ in s.chars().count()..width {
            self.byte(b' ');
        }
        self
    }

    /// Appends `v` in decimal (`{}`).
    pub fn u64(&mut self, mut v: u64) -> &mut Self {
        let mut digits = [0u8; 20];
        let mut n = 0;
        loop {
            if let Some(d) = digits.get_mut(n) {
                *d = b'0' + (v % 10) as u8;
            }
            n += 1;
            v /= 10;
            if v == 0 {
                break;
            }
        }
        for &d in digits.iter().take(n).rev() {
            self.byte(d);
        }
        self
    }

    /// Appends `v` in decimal (`{}`).
    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.u64(u64::from(v))
    }

    /// Appends `v` in decimal (`{}`).
    pub fn usize(&mut self, v: usize) -> &mut Self {
        self.u64(v as u64)
    }

    /// Appends `v` in decimal (`{}`).
    pub fn i64(&mut self, v: i64) -> &mut Self {
        if v < 0 {
            self.byte(b'-');
        }
        self.u64(v.unsigned_abs())
    }

    /// Appends `v` in lowercase hexadecimal, zero-padded to `width` digits
    /// (`{:0width$x}`).
    pub fn hex(&mut self, v: u32, width: u32) -> &mut Self {
        let digits = (32 - v.leading_zeros()).div_ceil(4).max(1);
        for _ in digits..width {
            self.byte(b'0');
        }
        for i in (0..digits).rev() {
            let nibble = (v >> (4 * i)) & 0xF;
            self.byte(if nibble < 10 {
                b'0' + nibble as u8
            } else {
                b'a' + (nibble - 10) as u8
            });
        }
        self
    }

    /// `NaN`, `inf` or `-inf` as core prints them; `false` if `v` is finite.
    fn non_finite(&mut self, v: f64) -> bool {
        if v.is_nan() {
            self.str("NaN");
        } else if v.is_infinite() {
            self.str(if v < 0.0 { "-inf" } else { "inf" });
        } else {
            return false;
        }
        true
    }

    /// Appends `v` in scientific notation with `decimals` digits after the
    /// point (`{:.decimals$e}`), e.g. `1.234e-13`, `0.0e0`.
    pub fn sci(&mut self, v: f64, decimals: u32) -> &mut Self {
        if self.non_finite(v) {
            return self;
        }
        if v.is_sign_negative() {
            self.byte(b'-');
        }
        let (digits, exp) = sci_digits(v.abs(), decimals);
        self.mantissa(digits, decimals);
        self.byte(b'e');
        self.i64(i64::from(exp))
    }

    /// Appends `v` in scientific notation, nine significant digits with the
    /// trailing zeros dropped (for `{:e}` of an `f32`): `0e0`, `1e-3`,
    /// `2.38418579e-7`.
    pub fn exp(&mut self, v: f32) -> &mut Self {
        let v = f64::from(v);
        if self.non_finite(v) {
            return self;
        }
        if v.is_sign_negative() {
            self.byte(b'-');
        }
        let (mut digits, exp) = sci_digits(v.abs(), 8);
        let mut decimals = 8;
        while decimals > 0 && digits % 10 == 0 {
            digits /= 10;
            decimals -= 1;
        }
        self.mantissa(digits, decimals);
        self.byte(b'e');
        self.i64(i64::from(exp))
    }

    /// Appends `v` with `decimals` digits after the point (`{:.decimals$}`,
    /// a negative value that rounds to zero keeps its sign, as in core),
    /// rounded half to even; values beyond ±1.8e19 print as `inf`.
    pub fn fixed(&mut self, v: f32, decimals: u32) -> &mut Self {
        let v = f64::from(v);
        if self.non_finite(v) {
            return self;
        }
        let scale = pow10(decimals);
        let scaled = v.abs() * scale as f64;
        if scaled >= u64::MAX as f64 {
            return self.str(if v < 0.0 { "-inf" } else { "inf" });
        }
        let n = round_half_even(scaled);
        if v.is_sign_negative() {
            self.byte(b'-');
        }
        self.u64(n.checked_div(scale).unwrap_or(0));
        if decimals > 0 {
            self.byte(b'.');
            self.zero_padded(n.checked_rem(scale).unwrap_or(0), decimals);
        }
        self
    }

    /// Appends `values` as `[a, b, …]`, each with [`Line::fixed`].
    pub fn fixed_list(&mut self, values: &[f32], decimals: u32) -> &mut Self {
        self.byte(b'[');
        for (i, &v) in values.iter().enumerate() {
            if i > 0 {
                self.str(", ");
            }
            self.fixed(v, decimals);
        }
        self.byte(b']');
        self
    }

    /// `digits` (1 + `decimals` of them) as `d.ddd`.
    fn mantissa(&mut self, digits: u64, decimals: u32) {
        let scale = pow10(decimals);
        self.u64(digits.checked_div(scale).unwrap_or(0));
        if decimals > 0 {
            self.byte(b'.');
            self.zero_padded(digits.checked_rem(scale).unwrap_or(0), decimals);
        }
    }

    /// `v` with leading zeros to `width` digits.
    fn zero_padded(&mut self, v: u64, width: u32) {
        let mut digits = 1;
        let mut rest = v / 10;
        while rest > 0 {
            digits += 1;
            rest /= 10;
        }
        for _ in digits..width {
            self.byte(b'0');
        }
        self.u64(v);
    }
}

/// 10^n, saturating at u64's range (n ≤ 19 is exact).
const fn pow10(n: u32) -> u64 {
    let mut p: u64 = 1;
    let mut i = 0;
    while i < n {
        p = p.saturating_mul(10);
        i += 1;
    }
    p
}

/// For finite `v ≥ 0`: the `1 + decimals` significant digits of `v`,
/// rounded half to even, and its decimal exponent (`0` for zero).
fn sci_digits(v: f64, decimals: u32) -> (u64, i32) {
    if v == 0.0 {
        return (0, 0);
    }
    let mut m = v;
    let mut exp = 0i32;
    // At most 309 steps up and 324 down (f64's range).
    while m >= 10.0 {
        m /= 10.0;
        exp += 1;
    }
    while m < 1.0 {
        m *= 10.0;
        exp -= 1;
    }
    // Once more with one correctly rounded operation where 10^|exp| is
    // exact in an f64 and a u64 (|exp| ≤ 19): closer to the exact decimal
    // expansion.
    if (-19..=19).contains(&exp) {
        let p = pow10(exp.unsigned_abs()) as f64;
        let once = if exp >= 0 { v / p } else { v * p };
        if (1.0..10.0).contains(&once) {
            m = once;
        }
    }
    let scale = pow10(decimals);
    let mut digits = round_half_even(m * scale as f64);
    if digits >= scale.saturating_mul(10) {
        digits /= 10;
        exp += 1;
    }
    (digits, exp)
}

/// `t ≥ 0` rounded to an integer, ties to even (as core rounds).
fn round_half_even(t: f64) -> u64 {
    let n = t as u64;
    let frac = t - n as f64;
    if frac > 0.5 || (frac == 0.5 && n % 2 == 1) {
        n.saturating_add(1)
    } else {
        n
    }
}

//! The number type of the body equations. The equations are written once, generic over
//! [`Scalar`]: in `f64` they are the model; in [`Dual`] (a value and one directional derivative)
//! the same code returns the exact directional derivative of every result (forward-mode
//! differentiation), which fmi2GetDirectionalDerivative and fmi2GetRealOutputDerivatives need.
//! Constants of the reduced body stay `f64`; only what depends on states and inputs is generic.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

pub trait Scalar:
    Copy
    + Debug
    + Default
    + PartialEq
    + From<f64>
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// Whether the number carries a derivative: branches that only skip work for exact zeros
    /// or exact rotations must not skip the derivative's part.
    const CARRIES_DERIVATIVE: bool;
    fn value(self) -> f64;
    /// Exactly zero, derivative included: a term with this coefficient can be skipped.
    fn is_zero(self) -> bool;
    fn sqrt(self) -> Self;
    fn sin(self) -> Self;
    fn cos(self) -> Self;
    fn zero() -> Self {
        Self::default()
    }
    /// out[i] += scale (m_i . x) for the rows i < out.len() of the row-major `m`, x.len() values
    /// a row: a coupling term applied to the state. Four partial sums a row (one chain of sums
    /// waits on itself); f64 takes the blocked kernel of [`crate::matvec`].
    fn add_scaled_mat_vec(m: &[f64], x: &[Self], scale: Self, out: &mut [Self]) {
        let k = x.len();
        if k == 0 {
            return;
        }
        for (o, row) in out.iter_mut().zip(m.chunks_exact(k)) {
            *o += scale * four_sums(row, x, |r, x| x * r);
        }
    }
}

impl Scalar for f64 {
    fn add_scaled_mat_vec(m: &[f64], x: &[f64], scale: f64, out: &mut [f64]) {
        crate::matvec::mat_vec((m, x.len()), x, out, crate::matvec::Store::AddScaled(scale));
    }
    const CARRIES_DERIVATIVE: bool = false;
    #[inline]
    fn value(self) -> f64 {
        self
    }
    #[inline]
    fn is_zero(self) -> bool {
        self == 0.0
    }
    #[inline]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline]
    fn sin(self) -> Self {
        f64::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        f64::cos(self)
    }
}

/// A value and its derivative along one direction: v + d epsilon with epsilon^2 = 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dual {
    pub v: f64,
    pub d: f64,
}

impl Dual {
    pub const fn new(v: f64, d: f64) -> Self {
        Self { v, d }
    }
}

impl From<f64> for Dual {
    #[inline]
    fn from(v: f64) -> Self {
        Self { v, d: 0.0 }
    }
}

impl Add for Dual {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self { v: self.v + o.v, d: self.d + o.d }
    }
}

impl Sub for Dual {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self { v: self.v - o.v, d: self.d - o.d }
    }
}

impl Mul for Dual {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        Self { v: self.v * o.v, d: self.d * o.v + self.v * o.d }
    }
}

impl Mul<f64> for Dual {
    type Output = Self;
    #[inline]
    fn mul(self, s: f64) -> Self {
        Self { v: self.v * s, d: self.d * s }
    }
}

impl Div<f64> for Dual {
    type Output = Self;
    #[inline]
    fn div(self, s: f64) -> Self {
        Self { v: self.v / s, d: self.d / s }
    }
}

impl Div for Dual {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let v = self.v / o.v;
        Self { v, d: (self.d - v * o.d) / o.v }
    }
}

impl Neg for Dual {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self { v: -self.v, d: -self.d }
    }
}

impl AddAssign for Dual {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.v += o.v;
        self.d += o.d;
    }
}

impl SubAssign for Dual {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        self.v -= o.v;
        self.d -= o.d;
    }
}

impl Scalar for Dual {
    const CARRIES_DERIVATIVE: bool = true;
    #[inline]
    fn value(self) -> f64 {
        self.v
    }
    #[inline]
    fn is_zero(self) -> bool {
        self.v == 0.0 && self.d == 0.0
    }
    fn sqrt(self) -> Self {
        let v = self.v.sqrt();
        Self { v, d: if self.d == 0.0 { 0.0 } else { 0.5 * self.d / v } }
    }
    fn sin(self) -> Self {
        Self { v: self.v.sin(), d: self.d * self.v.cos() }
    }
    fn cos(self) -> Self {
        Self { v: self.v.cos(), d: -self.d * self.v.sin() }
    }
}

/// The constant `x` as a scalar.
#[inline]
pub fn c<T: Scalar>(x: f64) -> T {
    T::from(x)
}

/// sum over j of mul(a_j, b_j) (over the shorter length) in four interleaved partial sums
/// (j mod 4), added pairwise, then the last terms: independent chains the processor keeps in
/// flight, where one chain of sums waits on each add.
#[inline(always)]
pub fn four_sums<A: Copy, B: Copy, T: Scalar>(a: &[A], b: &[B], mul: impl Fn(A, B) -> T) -> T {
    let k = a.len().min(b.len());
    let (a, b) = (&a[..k], &b[..k]);
    let mut s = [T::zero(); 4];
    for (x, y) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for l in 0..4 {
            s[l] += mul(x[l], y[l]);
        }
    }
    let mut sum = (s[0] + s[1]) + (s[2] + s[3]);
    for j in k - k % 4..k {
        sum += mul(a[j], b[j]);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f<T: Scalar>(x: T) -> T {
        // a little of everything the body uses
        let y = x * x * 3.0 - x / (x + c(2.0));
        y.sqrt() * y.sin() + y.cos() - (-x)
    }

    #[test]
    fn dual_derivative_equals_central_differences() {
        for x in [0.3, 1.7, 4.2] {
            let d = f(Dual::new(x, 1.0));
            assert_eq!(d.v, f(x));
            let h = 1e-5;
            let fd = (f(x + h) - f(x - h)) / (2.0 * h);
            assert!((d.d - fd).abs() <= 1e-8 * fd.abs().max(1.0), "{x}: {} vs {fd}", d.d);
        }
    }
}

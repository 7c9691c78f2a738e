//! Double-double accumulation of products (Ogita, Rump and Oishi's Dot2): each product's
//! rounding error found exactly (by FMA, or Dekker's splitting where the CPU has none) and each
//! addition's by TwoSum, the errors summed on the side and added once at the end. The sum is as
//! accurate as if computed in twice the precision, then rounded: what the residuals of
//! iterative refinement need (a slender part's reactions are 1e-6 of the terms summed).

/// (hi, lo) += a * b. `FMA`: the product's error by one fused multiply-add (only where the
/// caller is compiled for the instruction: `f64::mul_add` otherwise calls libm's software fma,
/// a hundred times slower).
#[inline(always)]
pub fn add_product<const FMA: bool>(hi: &mut f64, lo: &mut f64, a: f64, b: f64) {
    let prod = a * b;
    let err = if FMA { a.mul_add(b, -prod) } else { product_error(a, b, prod) };
    let s = *hi + prod;
    let bp = s - *hi;
    let t = (*hi - (s - bp)) + (prod - bp);
    *hi = s;
    *lo += t + err;
}

/// The rounding error of p = a * b (exactly a * b - p), by Dekker's splitting.
#[inline(always)]
pub fn product_error(a: f64, b: f64, p: f64) -> f64 {
    const SPLIT: f64 = 134_217_729.0; // 2^27 + 1
    let t = SPLIT * a;
    let a_hi = t - (t - a);
    let a_lo = a - a_hi;
    let t = SPLIT * b;
    let b_hi = t - (t - b);
    let b_lo = b - b_hi;
    ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo
}

#[cfg(test)]
mod tests {
    #[test]
    fn product_error_is_exact() {
        for (a, b) in [(0.1, 0.3), (1e10 / 3.0, 7.0 / 3.0), (-2.5e-8, 1.0 / 7.0), (123456.789, -9.87654321e-5)] {
            let p = a * b;
            assert_eq!(super::product_error(a, b, p), a.mul_add(b, -p));
        }
    }
}

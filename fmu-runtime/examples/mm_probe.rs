use fmu_runtime::matmul::mat_mul;
use std::time::Instant;
fn main() {
    for &(r, k, c) in &[
        (212usize, 212usize, 212usize),
        (200, 200, 200),
        (208, 208, 208),
        (216, 216, 216),
        (204, 204, 204),
        (212, 212, 216),
        (216, 212, 212),
        (212, 216, 212),
    ] {
        let a: Vec<f64> = (0..r * k).map(|v| ((v * 37 % 101) as f64 - 50.0) / 7.3).collect();
        let b: Vec<f64> = (0..k * c).map(|v| ((v * 53 % 97) as f64 - 48.0) / 11.9).collect();
        let mut out = vec![0.0; r * c];
        let reps = (2e9 / (2.0 * (r * k * c) as f64)) as usize;
        let mut best = f64::MAX;
        for _ in 0..5 {
            let t = Instant::now();
            for _ in 0..reps {
                mat_mul(r, k, c, &a, &b, &mut out);
                std::hint::black_box(&out);
            }
            best = best.min(t.elapsed().as_secs_f64() / reps as f64);
        }
        println!("{r}x{k}x{c}: {:.1} GFLOP/s", 2.0 * (r * k * c) as f64 / best / 1e9);
    }
}

use bikedyn_runtime::eigen::*;
use bikedyn_runtime::CanonicalMatrices;
use nalgebra::Matrix2;

fn published() -> CanonicalMatrices {
    CanonicalMatrices {
        m0: Matrix2::new(80.81722, 2.31941332208709, 2.31941332208709, 0.29784188199686),
        c1: Matrix2::new(0.0, 33.86641391492494, -0.85035641456978, 1.68540397397560),
        k0: Matrix2::new(-80.95, -2.59951685249872, -2.59951685249872, -0.80329488458618),
        k2: Matrix2::new(0.0, 76.59734589573222, 0.0, 2.65431523794604),
        g: 9.81,
    }
}

#[test]
fn eigen_scratch() {
    let c = published();
    for v in 0..=10 {
        let z = eigenvalues(&c, v as f64).unwrap();
        println!("{v} {:?}", z);
    }
    let n = 1_000_000;
    let t = std::time::Instant::now();
    let mut acc = 0.0;
    for i in 0..n {
        let z = eigenvalues(&c, 10.0 * i as f64 / n as f64).unwrap();
        acc += z[0].re;
    }
    println!("{} ns/call ({acc})", t.elapsed().as_nanos() as f64 / n as f64);
    let s = eigen_sweep(&c, &[0.0, 0.5, 0.7, 1.0, 5.0, 10.0, -3.0]).unwrap();
    for p in &s.points {
        println!("{} {:?} {:?}", p.v, p.modes, p.eigenvalues);
    }
}

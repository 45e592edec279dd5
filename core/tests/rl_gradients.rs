//! The MLP's gradients, plain and layer-normed (`Mlp::with_layer_norm`), proven two ways: central
//! finite differences of the same network evaluated in f64, and PyTorch's numbers for a fixed
//! network (the normed one's in `rl_layer_norm.rs`). Plus a tiny end-to-end fit as a regression
//! guard.

// Inside `mod rl` so that `cargo test rl` selects these tests with the unit tests of `dualrep_core::rl`.
mod rl {
    use dualrep_core::rl::kernels;
    use dualrep_core::rl::{Adam, AdamConfig, Mlp, MlpWorkspace, mse_loss};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use crate::support::gradient_check::{
        analytic, assert_close, assert_frozen_pass_is_the_same, central_differences, check,
        fill_problem, forward_backward, mse_f64,
    };

    // ----------------------------------------------------------------------------------------
    // Finite differences
    // ----------------------------------------------------------------------------------------

    /// Network shapes to check: sizes on both sides of 5 (nalgebra's own gemm changes code path
    /// there; ours must not care), and a critic-like scalar output.
    const SHAPES: [Shape; 3] = [
        (7, &[9, 8], 6, 10),
        (3, &[5, 4], 2, 4),
        (10, &[32, 24], 1, 16),
    ];

    // Central differences (`support::gradient_check::STEP`) of the f64 evaluation: between ReLU
    // kinks the plain network's loss is quadratic along any one coordinate, so they carry no
    // truncation error; a layer norm makes it not quadratic, and its truncation error, of order
    // STEP^2 times the third derivative, stays far below f32's rounding.

    /// Both kinds of network, each with the relative error its central differences allow.
    const KINDS: [(bool, f64); 2] = [(false, 2e-4), (true, 5e-4)];

    struct Problem {
        mlp: Mlp,
        ws: MlpWorkspace,
        target: Vec<f32>,
    }

    impl Problem {
        fn new(n_in: usize, hidden: &[usize], n_out: usize, batch: usize, seed: u64) -> Self {
            Self::of_kind(n_in, hidden, n_out, batch, seed, false)
        }

        /// With `layer_norm`, the network normed, its gains and biases moved away from 1 and 0
        /// so that their gradients and every path through them are exercised.
        fn of_kind(
            n_in: usize,
            hidden: &[usize],
            n_out: usize,
            batch: usize,
            seed: u64,
            layer_norm: bool,
        ) -> Self {
            let mut mlp = Mlp::new(n_in, hidden, n_out, &mut ChaCha8Rng::seed_from_u64(seed));
            if layer_norm {
                mlp = mlp.with_layer_norm();
                let first_norm = mlp.layers().iter().map(|l| l.len()).sum::<usize>();
                for (k, p) in mlp.params_mut()[first_norm..].iter_mut().enumerate() {
                    *p += 0.3 * (0.9 * k as f32 + seed as f32).sin();
                }
            }
            let mut ws = mlp.workspace(batch);
            let target = fill_problem(&mut ws, n_out, seed);
            Self { mlp, ws, target }
        }

        /// Forward, MSE, backward with the input gradient; returns (dL/dparams, dL/dinput).
        fn analytic(&mut self) -> (Vec<f32>, Vec<f32>) {
            analytic(&mut self.mlp, &mut self.ws, &self.target)
        }

        /// The same loss in f64 ([`mse_f64`]) at other parameters and input.
        fn loss_f64(&self, params: &[f64], input: &[f64]) -> f64 {
            mse_f64(&self.mlp, &self.target, params, input)
        }

        /// Central differences of [`Problem::loss_f64`]: (dL/dparams, dL/dinput).
        fn numeric(&self) -> (Vec<f64>, Vec<f64>) {
            central_differences(&self.mlp, &self.ws, |p, x| self.loss_f64(p, x))
        }
    }

    #[test]
    fn f32_forward_matches_the_f64_evaluation() {
        for ((seed, &(n_in, hidden, n_out, batch)), (norm, _)) in cases() {
            let mut problem = Problem::of_kind(n_in, hidden, n_out, batch, seed as u64, norm);
            let (_, _) = problem.analytic();
            let out = problem.ws.output().as_slice();
            let loss: f64 = out
                .iter()
                .zip(&problem.target)
                .map(|(&o, &y)| f64::from(o - y).powi(2))
                .sum::<f64>()
                / out.len() as f64;
            let params: Vec<f64> = problem.mlp.params().iter().map(|&p| f64::from(p)).collect();
            let input: Vec<f64> = problem.ws.input().iter().map(|&x| f64::from(x)).collect();
            let loss_f64 = problem.loss_f64(&params, &input);
            assert!(
                (loss - loss_f64).abs() < 1e-6 * loss_f64,
                "{loss} vs {loss_f64}"
            );
        }
    }

    /// `(n_in, hidden, n_out, batch)`.
    type Shape = (usize, &'static [usize], usize, usize);

    /// Every shape (numbered, the number its seed) of each kind.
    fn cases() -> impl Iterator<Item = ((usize, &'static Shape), (bool, f64))> {
        KINDS
            .into_iter()
            .flat_map(|kind| SHAPES.iter().enumerate().map(move |shape| (shape, kind)))
    }

    /// Weights, biases (and a layer norm's gains and biases) and the input, on every path.
    #[test]
    fn parameter_and_input_gradients_match_central_differences() {
        kernels::on_every_path(|path| {
            for ((seed, &(n_in, hidden, n_out, batch)), (norm, tolerance)) in cases() {
                let mut problem = Problem::of_kind(n_in, hidden, n_out, batch, seed as u64, norm);
                let (grads, input_grad) = problem.analytic();
                let (numeric, numeric_input) = problem.numeric();
                let shape = format!("{n_in}->{hidden:?}->{n_out} x{batch}, layer norm {norm}");
                check(
                    &format!("{path}: dL/dparams {shape}"),
                    &grads,
                    &numeric,
                    tolerance,
                );
                let name = format!("{path}: dL/dinput {shape}");
                check(&name, &input_grad, &numeric_input, tolerance);
            }
        });
    }

    #[test]
    fn backward_input_gives_the_same_input_gradient_and_leaves_parameters_alone() {
        kernels::on_every_path(|path| {
            for (norm, _) in KINDS {
                let mut p = Problem::of_kind(10, &[32, 24], 1, 16, 3, norm);
                let what = format!("{path}, layer norm {norm}");
                assert_frozen_pass_is_the_same(&mut p.mlp, &mut p.ws, &p.target, &what);
            }
        });
    }

    #[test]
    fn parameter_gradients_accumulate_until_zero_grad() {
        let mut problem = Problem::new(7, &[9, 8], 6, 10, 0);
        let (once, _) = problem.analytic();
        problem.mlp.backward(&mut problem.ws); // the same output gradient again
        for (twice, once) in problem.mlp.grads().iter().zip(&once) {
            assert!(
                (twice - 2.0 * once).abs() <= 1e-5 * once.abs().max(1e-3),
                "{twice} vs 2 x {once}"
            );
        }
    }

    // ----------------------------------------------------------------------------------------
    // PyTorch
    // ----------------------------------------------------------------------------------------

    // Printed by `python3 benches/reference/torch_reference_values.py` with torch 2.15.0+cu132
    // (the PyPI wheel, run on the CPU):
    // the MLP 6 -> [8, 7] -> 6 with the formula parameters below, batch 9, MSE loss, and two
    // steps of torch.optim.Adam(lr = 0.01), each a zero_grad, forward, backward and step.
    const LOSS_0: f32 = 0.6706128;
    #[rustfmt::skip]
    const OUTPUT_0: [f32; 54] = [-0.057088196, 0.31941825, -0.8055872, -0.0056853294, 0.42453414, 0.20458904, -0.13310772, 0.45378125, -0.98424494, 0.19858742, 0.21600454, 0.3955723, -0.07568562, 0.33090508, -0.8087623, -0.011153832, 0.4380745, 0.18439254, -0.09797692, 0.4123826, -0.940907, 0.15784135, 0.2498984, 0.3720745, -0.0951525, 0.34185266, -0.810046, -0.019668251, 0.45549682, 0.15988399, -0.053171962, 0.35871476, -0.88398767, 0.10362193, 0.29574895, 0.33938676, -0.0910362, 0.31583947, -0.7648556, -0.07931072, 0.52335536, 0.090904385, -0.04701835, 0.34384, -0.8619471, 0.07672, 0.32469946, 0.31141466, -0.09101874, 0.32760972, -0.78718305, -0.048760682, 0.48777694, 0.12779126];
    #[rustfmt::skip]
    const INPUT_GRAD_0: [f32; 54] = [-0.0051711225, -0.003087035, 0.003519566, 0.0049699945, -0.00086063065, -0.00543043, -0.00059333304, -0.013870976, -0.006827607, 0.010218222, 0.012294332, -0.0036407833, -0.0051412056, 0.0014067774, 0.0058938274, 0.0017464065, -0.004959504, -0.00439973, -0.0017550422, -0.0077049863, -0.002367108, 0.006438589, 0.0058117374, -0.0033293234, -0.00866184, -0.0019319188, 0.0076282686, 0.006013024, -0.0044113146, -0.008373068, 0.014254384, 0.0022773743, -0.013035994, -0.0092516, 0.008086409, 0.0135778105, 0.0014179857, 0.00083568145, -0.0009708981, -0.0013551096, 0.0002459176, 0.0014866749, 0.002466991, -0.0015246167, -0.0032826576, -0.00023159737, 0.0031587533, 0.0019215232, -0.0064203283, -0.0068219635, 0.0027705946, 0.008304225, 0.0016721463, -0.007409631];
    #[rustfmt::skip]
    const GRAD_0_PROBE: [f32; 16] = [-0.012841318, 0.024456216, 0.0, -0.0069570346, 0.0051837605, 0.029501038, 0.03339107, 0.0011176495, -0.00809159, 0.0, 0.00033020336, -0.037661593, 0.0015290091, 0.0, 0.0063666543, 0.08731307];
    const GRAD_0_SUM: f32 = 0.003683329;
    const GRAD_0_ABS_SUM: f32 = 3.4373832;
    const LOSS_1: f32 = 0.6411698;
    #[rustfmt::skip]
    const PARAMS_2_PROBE: [f32; 16] = [0.069781564, 0.46319386, -0.20646377, -0.40194952, 0.3337252, 0.28522182, -0.4584613, -0.17996877, 0.5127145, 0.0026493862, -0.51050854, 0.1773108, 0.4252071, -0.30101198, -0.3648778, 0.39292893];
    const PARAMS_2_SUM: f32 = 0.4141388;
    const PARAMS_2_ABS_SUM: f32 = 52.91996;
    /// Parameter indices printed by the script.
    const PROBE: [usize; 16] = [
        0, 11, 22, 33, 44, 55, 66, 77, 88, 99, 110, 121, 132, 143, 154, 165,
    ];

    /// The script's network: formulas in f64, rounded to f32, identical to the Python ones.
    fn torch_problem() -> (Mlp, MlpWorkspace, Vec<f32>) {
        let mut mlp = Mlp::zeros(6, &[8, 7], 6);
        for (k, p) in mlp.params_mut().iter_mut().enumerate() {
            *p = (0.5 * (1.3 * k as f64 + 0.1).sin()) as f32;
        }
        let mut ws = mlp.workspace(9);
        for (k, x) in ws.input_mut().iter_mut().enumerate() {
            *x = (0.5 * k as f64).cos() as f32;
        }
        let target = (0..54).map(|k| (0.3 * k as f64).sin() as f32).collect();
        (mlp, ws, target)
    }

    fn sums(values: &[f32]) -> [f32; 2] {
        let sum: f64 = values.iter().map(|&v| f64::from(v)).sum();
        let abs_sum: f64 = values.iter().map(|&v| f64::from(v.abs())).sum();
        [sum as f32, abs_sum as f32]
    }

    #[test]
    fn forward_loss_and_gradients_agree_with_pytorch() {
        kernels::on_every_path(|path| {
            let (mut mlp, mut ws, target) = torch_problem();
            let loss = forward_backward(&mut mlp, &mut ws, &target);
            assert_close(&format!("{path}: loss"), &[loss], &[LOSS_0], 1e-6);
            assert_close(
                &format!("{path}: output"),
                ws.output().as_slice(),
                &OUTPUT_0,
                1e-5,
            );
            assert_close(
                &format!("{path}: dL/dinput"),
                ws.input_grad().as_slice(),
                &INPUT_GRAD_0,
                1e-4,
            );
            let probe: Vec<f32> = PROBE.iter().map(|&i| mlp.grads()[i]).collect();
            assert_close(
                &format!("{path}: dL/dparams (probe)"),
                &probe,
                &GRAD_0_PROBE,
                1e-4,
            );
            assert_close(
                &format!("{path}: dL/dparams (sum, sum of |.|)"),
                &sums(mlp.grads()),
                &[GRAD_0_SUM, GRAD_0_ABS_SUM],
                1e-4,
            );
        });
    }

    #[test]
    fn two_adam_steps_agree_with_pytorch() {
        kernels::on_every_path(|path| {
            let (mut mlp, mut ws, target) = torch_problem();
            let mut adam = Adam::new(AdamConfig::with_lr(0.01), &[mlp.params().len()]);
            forward_backward(&mut mlp, &mut ws, &target);
            adam.step([mlp.params_and_grads()]);
            let loss_1 = forward_backward(&mut mlp, &mut ws, &target);
            adam.step([mlp.params_and_grads()]);
            assert_close(
                &format!("{path}: loss after one step"),
                &[loss_1],
                &[LOSS_1],
                1e-6,
            );
            let probe: Vec<f32> = PROBE.iter().map(|&i| mlp.params()[i]).collect();
            assert_close(
                &format!("{path}: params after two steps (probe)"),
                &probe,
                &PARAMS_2_PROBE,
                1e-5,
            );
            assert_close(
                &format!("{path}: params after two steps (sum, sum of |.|)"),
                &sums(mlp.params()),
                &[PARAMS_2_SUM, PARAMS_2_ABS_SUM],
                1e-5,
            );
        });
    }

    // ----------------------------------------------------------------------------------------
    // End to end
    // ----------------------------------------------------------------------------------------

    /// Guards the whole loop (init, forward, backward, Adam): a [64, 64] network fits
    /// y = sin(x) on 256 points of [-pi, pi], full batch.
    #[test]
    fn fits_sin_on_256_points_within_a_few_hundred_adam_steps() {
        let n = 256;
        let mut mlp = Mlp::new(1, &[64, 64], 1, &mut ChaCha8Rng::seed_from_u64(0));
        let mut ws = mlp.workspace(n);
        let mut adam = Adam::new(AdamConfig::with_lr(3e-3), &[mlp.params().len()]);
        let xs: Vec<f32> = (0..n)
            .map(|i| -std::f32::consts::PI + 2.0 * std::f32::consts::PI * i as f32 / (n - 1) as f32)
            .collect();
        let ys: Vec<f32> = xs.iter().map(|x| x.sin()).collect();
        ws.input_mut().as_mut_slice().copy_from_slice(&xs);
        let mut losses = Vec::new();
        for _ in 0..400 {
            mlp.zero_grad();
            mlp.forward(&mut ws);
            let (out, grad) = ws.output_and_grad_mut();
            losses.push(mse_loss(out.as_slice(), &ys, grad.as_mut_slice()));
            mlp.backward(&mut ws);
            adam.step([mlp.params_and_grads()]);
        }
        let last = losses[losses.len() - 1];
        eprintln!(
            "sin fit: MSE {:.3e} at start, {:.3e} after 400 steps",
            losses[0], last
        );
        assert!(
            losses[0] > 0.1,
            "an untrained network should not fit sin: {}",
            losses[0]
        );
        assert!(last < 1e-3, "MSE after 400 Adam steps: {last}");
    }
}

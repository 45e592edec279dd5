//! The layer-normed MLP (`Mlp::with_layer_norm`, the env critic of `critic_layer_norm`), proven
//! as the plain one is in `rl_gradients.rs`: central finite differences of an f64 evaluation on
//! every kernel path, and PyTorch's numbers for a fixed network (`Linear -> LayerNorm -> ReLU`).

// Inside `mod rl` so that `cargo test rl` selects these tests with the unit tests of `dualrep_core::rl`.
mod rl {
    use dualrep_core::rl::kernels;
    use dualrep_core::rl::{Adam, AdamConfig, Mlp, MlpWorkspace, mse_loss};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Sizes on both sides of 5 and a critic-like scalar output, as `rl_gradients.rs` checks.
    const SHAPES: [(usize, &[usize], usize, usize); 3] = [
        (7, &[9, 8], 6, 10),
        (3, &[5, 4], 2, 4),
        (10, &[32, 24], 1, 16),
    ];

    /// Central differences' half-width on the f64 evaluation. The normalisation makes the loss
    /// no longer quadratic along a coordinate, so they carry a truncation error of order
    /// STEP^2 times the third derivative, far below f32's rounding at this step.
    const STEP: f64 = 1e-6;
    const EPS: f64 = 1e-5;

    struct Problem {
        mlp: Mlp,
        ws: MlpWorkspace,
        target: Vec<f32>,
    }

    impl Problem {
        fn new(n_in: usize, hidden: &[usize], n_out: usize, batch: usize, seed: u64) -> Self {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut mlp = Mlp::new(n_in, hidden, n_out, &mut rng).with_layer_norm();
            // Gains and biases away from their initial 1 and 0, so that their gradients and the
            // paths through them are all exercised.
            let first_norm = mlp.layers().iter().map(|l| l.len()).sum::<usize>();
            for (k, p) in mlp.params_mut()[first_norm..].iter_mut().enumerate() {
                *p += 0.3 * (0.9 * k as f32 + seed as f32).sin();
            }
            let mut ws = mlp.workspace(batch);
            for (k, x) in ws.input_mut().iter_mut().enumerate() {
                *x = (0.7 * k as f32 + seed as f32).sin() * 2.0;
            }
            let target = (0..n_out * batch).map(|k| (0.3 * k as f32).cos()).collect();
            Self { mlp, ws, target }
        }

        /// Forward, MSE, backward with the input gradient; returns (dL/dparams, dL/dinput).
        fn analytic(&mut self) -> (Vec<f32>, Vec<f32>) {
            self.mlp.zero_grad();
            self.mlp.forward(&mut self.ws);
            let (out, grad) = self.ws.output_and_grad_mut();
            mse_loss(out.as_slice(), &self.target, grad.as_mut_slice());
            self.mlp.backward_with_input_grad(&mut self.ws);
            (
                self.mlp.grads().to_vec(),
                self.ws.input_grad().as_slice().to_vec(),
            )
        }

        /// The same loss in f64 with plain loops: every layer's weight and bias in order, then
        /// every norm's gain and bias; the variance biased, as PyTorch's.
        fn loss_f64(&self, params: &[f64], input: &[f64]) -> f64 {
            let layers = self.mlp.layers();
            let n_in = layers[0].n_in;
            let mut norm_offset = layers.iter().map(|l| l.len()).sum::<usize>();
            let norm_offsets: Vec<usize> = layers[..layers.len() - 1]
                .iter()
                .map(|l| {
                    let at = norm_offset;
                    norm_offset += 2 * l.n_out;
                    at
                })
                .collect();
            let mut sum = 0.0;
            for (sample, target) in input
                .chunks_exact(n_in)
                .zip(self.target.chunks_exact(self.mlp.n_out()))
            {
                let mut x = sample.to_vec();
                for (l, layer) in layers.iter().enumerate() {
                    let (w, b) = (layer.offset, layer.offset + layer.n_out * layer.n_in);
                    let z: Vec<f64> = (0..layer.n_out)
                        .map(|o| {
                            let row = &params[w + o * layer.n_in..w + (o + 1) * layer.n_in];
                            params[b + o] + row.iter().zip(&x).map(|(w, x)| w * x).sum::<f64>()
                        })
                        .collect();
                    x = match norm_offsets.get(l) {
                        None => z,
                        Some(&at) => {
                            let n = z.len() as f64;
                            let mean = z.iter().sum::<f64>() / n;
                            let var = z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
                            let inv = 1.0 / (var + EPS).sqrt();
                            let (gain, bias) = (&params[at..], &params[at + z.len()..]);
                            z.iter()
                                .enumerate()
                                .map(|(j, v)| (gain[j] * (v - mean) * inv + bias[j]).max(0.0))
                                .collect()
                        }
                    };
                }
                sum += x
                    .iter()
                    .zip(target)
                    .map(|(o, &y)| (o - f64::from(y)).powi(2))
                    .sum::<f64>();
            }
            sum / self.target.len() as f64
        }

        /// Central differences of [`Problem::loss_f64`]: (dL/dparams, dL/dinput).
        fn numeric(&self) -> (Vec<f64>, Vec<f64>) {
            let params = self.mlp.params().iter().map(|&p| f64::from(p)).collect();
            let input = self.ws.input().iter().map(|&x| f64::from(x)).collect();
            let mut point: [Vec<f64>; 2] = [params, input];
            let mut derivative = [Vec::new(), Vec::new()];
            for which in 0..2 {
                for i in 0..point[which].len() {
                    let original = point[which][i];
                    point[which][i] = original + STEP;
                    let plus = self.loss_f64(&point[0], &point[1]);
                    point[which][i] = original - STEP;
                    let minus = self.loss_f64(&point[0], &point[1]);
                    point[which][i] = original;
                    derivative[which].push((plus - minus) / (2.0 * STEP));
                }
            }
            let [d_params, d_input] = derivative;
            (d_params, d_input)
        }
    }

    /// Largest |analytic - numeric| / max(|analytic|, |numeric|, 1e-4); panics past `tolerance`.
    fn check(name: &str, analytic: &[f32], numeric: &[f64], tolerance: f64) {
        assert_eq!(analytic.len(), numeric.len());
        let mut worst = 0.0f64;
        for (i, (&a, &n)) in analytic.iter().zip(numeric).enumerate() {
            let a = f64::from(a);
            let err = (a - n).abs() / a.abs().max(n.abs()).max(1e-4);
            assert!(
                err <= tolerance,
                "{name}[{i}]: analytic {a:e}, central difference {n:e}"
            );
            worst = worst.max(err);
        }
        assert!(
            numeric.iter().any(|&n| n.abs() > 1e-3),
            "{name}: all gradients near zero"
        );
        eprintln!(
            "{name}: {} coordinates, max relative error {worst:.2e}",
            analytic.len()
        );
    }

    #[test]
    fn gains_biases_and_weights_match_central_differences_on_every_path() {
        kernels::on_every_path(|path| {
            for (seed, &(n_in, hidden, n_out, batch)) in SHAPES.iter().enumerate() {
                let mut problem = Problem::new(n_in, hidden, n_out, batch, seed as u64);
                let (grads, input_grad) = problem.analytic();
                let (numeric, numeric_input) = problem.numeric();
                let shape = format!("{n_in}->{hidden:?}->{n_out} x{batch}");
                check(
                    &format!("{path}: dL/dparams {shape}"),
                    &grads,
                    &numeric,
                    5e-4,
                );
                check(
                    &format!("{path}: dL/dinput {shape}"),
                    &input_grad,
                    &numeric_input,
                    5e-4,
                );
            }
        });
    }

    #[test]
    fn a_frozen_normed_critic_passes_back_the_same_input_gradient_and_keeps_its_own() {
        kernels::on_every_path(|path| {
            let mut problem = Problem::new(10, &[32, 24], 1, 16, 3);
            let (_, input_grad) = problem.analytic();
            problem.mlp.zero_grad();
            problem.mlp.forward(&mut problem.ws);
            problem.mlp.backward_input(&mut problem.ws);
            assert_eq!(
                problem.ws.input_grad().as_slice(),
                &input_grad[..],
                "{path}"
            );
            assert!(problem.mlp.grads().iter().all(|&g| g == 0.0), "{path}");
        });
    }

    #[test]
    fn an_input_gradient_on_some_columns_has_the_bits_of_the_whole_batch_pass() {
        kernels::on_every_path(|path| {
            let mut problem = Problem::new(10, &[40, 30], 1, 37, 5);
            problem.mlp.forward(&mut problem.ws);
            let picked: Vec<usize> = (1..37).filter(|i| i % 3 != 0).collect();
            for (i, g) in problem.ws.output_grad_mut().iter_mut().enumerate() {
                *g = if picked.contains(&i) {
                    (i as f32 * 0.37).cos()
                } else {
                    0.0
                };
            }
            let mut sub = problem.mlp.workspace(37);
            problem
                .mlp
                .backward_input_columns(&problem.ws, &picked, &mut sub);
            problem.mlp.backward_input(&mut problem.ws);
            for (c, &i) in picked.iter().enumerate() {
                let bits = |ws: &MlpWorkspace, c: usize| -> Vec<u32> {
                    ws.input_grad()
                        .column(c)
                        .iter()
                        .map(|v| v.to_bits())
                        .collect()
                };
                assert_eq!(bits(&sub, c), bits(&problem.ws, i), "{path}: sample {i}");
            }
        });
    }

    #[test]
    fn layer_norms_draw_nothing_and_name_their_tensors_as_pytorch_does() {
        let plain = Mlp::new(3, &[5, 4], 2, &mut ChaCha8Rng::seed_from_u64(9));
        let normed = Mlp::new(3, &[5, 4], 2, &mut ChaCha8Rng::seed_from_u64(9)).with_layer_norm();
        assert_eq!(&normed.params()[..plain.params().len()], plain.params());
        let names: Vec<_> = normed
            .named_parameters()
            .map(|t| (t.name, t.shape))
            .collect();
        let tail: Vec<(String, Vec<usize>)> = vec![
            ("norms.0.weight".into(), vec![5]),
            ("norms.0.bias".into(), vec![5]),
            ("norms.1.weight".into(), vec![4]),
            ("norms.1.bias".into(), vec![4]),
        ];
        assert_eq!(names[6..], tail[..]);
        // PyTorch's initialisation: gains 1, biases 0.
        assert_eq!(&normed.params()[plain.params().len()..][..5], &[1.0; 5]);
        assert_eq!(&normed.params()[plain.params().len() + 5..][..5], &[0.0; 5]);
    }

    // Printed by `python3 benches/reference/torch_layer_norm_values.py` with torch 2.15.0+cu132
    // (the PyPI wheel, run on the CPU): the MLP 6 -> [8, 7] -> 6 with a layer norm before each
    // hidden ReLU and the formula parameters below, batch 9, MSE loss, and two steps of
    // torch.optim.Adam(lr = 0.01), each a zero_grad, forward, backward and step.
    const LOSS_0: f32 = 0.80314636;
    #[rustfmt::skip]
    const OUTPUT_0: [f32; 54] = [-0.42818528, 0.67831385, -1.1147563, 0.22143158, 0.30321598, 0.2074237, -0.33199382, 0.5057743, -0.8839088, -0.043587126, 0.5746965, -0.04213333, -0.57960325, 0.76848215, -1.1342473, 0.16820726, 0.42359066, 0.03248471, -0.33826548, 0.5149393, -0.8950088, -0.03171265, 0.5632891, -0.032385796, -0.5785517, 0.6606955, -0.9309952, -0.10925863, 0.74625957, -0.30164984, -0.34935325, 0.5277434, -0.9081906, -0.019531399, 0.55338204, -0.025788844, -0.4410302, 0.5812246, -0.91788423, -0.054638967, 0.62962, -0.13518599, -0.37018138, 0.5473724, -0.92456806, -0.008117974, 0.54812586, -0.027239501, -0.42293876, 0.61655945, -1.0029508, 0.07126504, 0.4760427, 0.030007154];
    #[rustfmt::skip]
    const INPUT_GRAD_0: [f32; 54] = [-0.030849664, -0.04676784, 0.005828983, 0.049886324, 0.020860083, -0.038726233, 0.0024104095, 0.0016604275, -0.0015220849, -0.0024747397, 0.00019810506, 0.0025807254, -0.019771026, 0.023697002, 0.03244887, -0.006336933, -0.03583911, -0.012836908, 0.0009280481, 0.000958186, -0.00041542097, -0.0011804355, -0.00021610889, 0.0010648174, -0.019869171, 0.0023906764, 0.021148182, 0.008923551, -0.016374102, -0.017683657, 0.004671662, 0.0038005898, -0.002638355, -0.0052121035, -0.00015010792, 0.005131796, -0.025983922, -0.008877171, 0.021234658, 0.020237662, -0.010407555, -0.025805682, 0.0038728733, 0.005588135, -0.00088323443, -0.0060606645, -0.0023592066, 0.0047984933, -0.028182605, -0.0019525969, 0.02713797, 0.016471347, -0.018325837, -0.026275627];
    #[rustfmt::skip]
    const GRAD_0: [f32; 197] = [-0.008415586, -0.004571347, 0.00039212173, 0.005259582, 0.008839315, 0.010254874, -0.07091204, -0.09390362, -0.09390434, -0.07091398, -0.030561414, 0.017273653, 0.044260196, 0.058039367, 0.057608478, 0.04307302, 0.017991789, -0.011494462, 0.0098353755, 0.0142363105, 0.0151517, 0.012357425, 0.006537622, -0.0008828197, 0.04003939, 0.05071046, 0.048965834, 0.035232667, 0.012873315, -0.012637873, -0.059140656, -0.061847493, -0.0494119, -0.02487855, 0.0057459297, 0.03496361, -0.019037504, -0.032353207, -0.037747722, -0.033900276, -0.021752859, -0.0042795837, 0.06337083, 0.06968954, 0.058945823, 0.033770114, 0.00032629818, -0.0331974, -0.01670483, -0.093381114, -0.024396453, 0.014698684, 0.010311725, 0.01583523, -0.03387913, 0.12751591, 0.05641927, 0.063478544, 0.033994876, 0.0, 0.0063927593, 0.020930685, 0.047941364, 0.07132228, 0.1777293, 0.13968997, 0.07390171, 0.0, 0.02946242, 0.054077115, 0.088192046, 0.099059716, -0.061651718, -0.112170264, -0.07715877, 0.0, -0.003826772, -0.050078064, -0.10334784, -0.09094459, 0.031844802, 0.018208046, 0.0028557342, 0.0, 0.0015199773, -9.414805e-05, 0.0062936917, 0.037583023, -0.196803, -0.12125586, -0.04524389, 0.0, -0.03528826, -0.031242765, -0.05837777, -0.12363237, 0.043059435, 0.04197857, 0.022008592, 0.0, 0.011105804, 0.015013974, 0.031411305, 0.03552957, -0.050598126, -0.029929044, -0.010358259, 0.0, -0.009365937, -0.0086068055, -0.012112807, -0.028917665, 0.10513772, 0.22081289, -0.18199141, 0.031885117, -0.19743232, 0.06889413, -0.047306173, -0.0612598, -0.09735725, -0.06465974, 0.0, -0.09628158, -0.25912988, 0.0, 0.04849986, 0.1325597, 0.045532864, 0.0, 0.105095655, 0.19396602, 0.0, -0.11574994, -0.24813057, -0.1211607, 0.0, -0.22329433, -0.49097455, 0.0, -0.0107893385, -0.009523904, -0.009650412, 0.0, -0.01942592, -0.056618907, 0.0, 0.048932012, 0.060290024, 0.060884617, 0.0, 0.068462595, 0.2210316, 0.0, -0.010559952, -0.033490747, -4.15314e-05, 0.0, -0.031417288, -0.045737296, 0.0, -0.1786221, 0.15702608, -0.3684768, -0.037289962, 0.13926244, -0.041308686, -0.020217787, -0.07845767, -0.0596541, 0.0, -0.0025920079, 0.0033589643, -0.08663573, 0.006641969, -0.01884989, -0.10320526, -0.054259494, 0.0, 0.0010169693, 0.01254446, -0.0784758, 0.010287486, -0.034715686, 0.16971119, -0.025753155, 0.0, -0.049844183, 0.30601394, 0.0, 0.19264168, 0.1971204, -0.03897557, 0.0, -0.09450619, 0.23312078, 0.0];
    const LOSS_1: f32 = 0.7049022;
    #[rustfmt::skip]
    const PARAMS_2: [f32; 197] = [0.058911923, 0.49766394, 0.19608654, -0.39775482, -0.43609393, 0.1388085, 0.5185552, 0.13066204, -0.42053956, -0.32734457, 0.27401328, 0.46502772, -0.016001923, -0.5006878, -0.28114715, 0.32098436, 0.42357075, -0.08373564, -0.5189656, -0.18306749, 0.39210197, 0.36429653, -0.22456834, -0.47515836, -0.07454273, 0.4458244, 0.28791872, -0.31777674, -0.48535553, 0.06399817, 0.51224416, 0.23281965, -0.35906807, -0.39608726, 0.14098334, 0.48023498, 0.13083787, -0.42010877, -0.32644883, 0.27472612, 0.5026741, 0.013560731, -0.5002663, -0.28031656, 0.32167548, 0.42359442, -0.12193351, -0.47993258, -0.1494156, 0.43098494, 0.40165353, -0.22642441, -0.4993375, -0.07740216, 0.4832365, 0.28556415, -0.3198187, -0.4855682, 0.030967694, 0.49287504, 0.1936913, -0.39856917, -0.43548512, 0.13716695, 0.47954226, 0.09063546, -0.46022356, -0.34612215, 0.23647377, 0.46283233, -0.016850213, -0.50059146, -0.24050379, 0.36147356, 0.4630249, -0.104536906, -0.47970653, -0.14287923, 0.4319866, 0.40237498, -0.22594272, -0.5123284, -0.06922223, 0.46340925, 0.29199874, -0.28258076, -0.48293972, 0.03277576, 0.51279044, 0.23242445, -0.3593162, -0.41539368, 0.1756142, 0.5191989, 0.13011372, -0.4209147, -0.36576387, 0.23549217, 0.46250206, 0.0026493862, -0.5001024, -0.27986354, 0.321991, 0.42317593, -0.08516948, -0.47917527, -0.14205661, 0.41242117, 0.4015002, -0.18778871, -0.4737975, -0.036965318, 0.44381738, 0.28463945, -0.28090006, -0.4835845, 0.07153568, 0.47309443, 0.23194838, -0.36028433, -0.39543405, 0.17739192, 0.4993858, 0.12957263, -0.42102802, -0.34548065, 0.2369624, 0.46271428, -0.017689027, -0.48118448, -0.27953592, 0.32270104, 0.44275627, -0.08583806, -0.47923, -0.14162596, 0.41267207, 0.40242106, -0.18816693, -0.4937387, -0.03628383, 0.48344246, 0.32408923, -0.30101198, -0.44520003, 0.072065376, 0.4930974, 0.19208819, -0.3995618, -0.43491158, 0.15787902, 0.4793522, 0.08936683, -0.44089943, -0.32953355, 0.2760534, 0.4848331, 0.001761238, -0.46183914, -0.24266139, 0.3426024, 0.4622746, -0.12556079, -0.47922024, -0.14122538, 0.3929708, 0.4005694, 0.81146604, 0.5261507, 0.96420527, 1.4639078, 1.3225329, 0.68190986, 0.55467844, 1.034026, 0.5125564, 0.23095201, -0.3604149, -0.4146507, 0.15383554, 0.47942737, 0.12872963, -0.46021098, 0.6751519, 1.236812, 1.5020185, 1.0013171, 0.53858835, 0.7214482, 1.3429257, 0.42260244, -0.12616083, -0.47943863, -0.16079693, 0.43315536, 0.36207154, -0.20888753];

    /// The script's network: formulas in f64, rounded to f32, identical to the Python ones.
    fn torch_problem() -> (Mlp, MlpWorkspace, Vec<f32>) {
        let mut mlp = Mlp::zeros(6, &[8, 7], 6).with_layer_norm();
        let gains = [167..175, 183..190];
        for (k, p) in mlp.params_mut().iter_mut().enumerate() {
            let gain = if gains.iter().any(|g| g.contains(&k)) {
                1.0
            } else {
                0.0
            };
            *p = (gain + 0.5 * (1.3 * k as f64 + 0.1).sin()) as f32;
        }
        let mut ws = mlp.workspace(9);
        for (k, x) in ws.input_mut().iter_mut().enumerate() {
            *x = (0.5 * k as f64).cos() as f32;
        }
        let target = (0..54).map(|k| (0.3 * k as f64).sin() as f32).collect();
        (mlp, ws, target)
    }

    fn forward_backward(mlp: &mut Mlp, ws: &mut MlpWorkspace, target: &[f32]) -> f32 {
        mlp.zero_grad();
        mlp.forward(ws);
        let (out, grad) = ws.output_and_grad_mut();
        let loss = mse_loss(out.as_slice(), target, grad.as_mut_slice());
        mlp.backward_with_input_grad(ws);
        loss
    }

    fn assert_close(name: &str, got: &[f32], want: &[f32], tolerance: f32) {
        assert_eq!(got.len(), want.len());
        let mut worst = 0.0f32;
        for (i, (&g, &w)) in got.iter().zip(want).enumerate() {
            let err = (g - w).abs() / w.abs().max(1e-2);
            assert!(err <= tolerance, "{name}[{i}]: {g:e}, PyTorch {w:e}");
            worst = worst.max(err);
        }
        eprintln!("{name}: max deviation from PyTorch {worst:.2e} (relative, absolute below 1e-2)");
    }

    #[test]
    fn forward_loss_gradients_and_two_adam_steps_agree_with_pytorch() {
        kernels::on_every_path(|path| {
            let (mut mlp, mut ws, target) = torch_problem();
            let mut adam = Adam::new(AdamConfig::with_lr(0.01), &[mlp.params().len()]);
            let loss_0 = forward_backward(&mut mlp, &mut ws, &target);
            assert_close(&format!("{path}: loss 0"), &[loss_0], &[LOSS_0], 1e-6);
            assert_close(
                &format!("{path}: output"),
                ws.output().as_slice(),
                &OUTPUT_0,
                1e-5,
            );
            let input_grad = ws.input_grad().as_slice();
            assert_close(
                &format!("{path}: dL/dinput"),
                input_grad,
                &INPUT_GRAD_0,
                1e-4,
            );
            assert_close(&format!("{path}: dL/dparams"), mlp.grads(), &GRAD_0, 1e-4);
            adam.step([mlp.params_and_grads()]);
            let loss_1 = forward_backward(&mut mlp, &mut ws, &target);
            adam.step([mlp.params_and_grads()]);
            assert_close(&format!("{path}: loss 1"), &[loss_1], &[LOSS_1], 1e-5);
            assert_close(
                &format!("{path}: params after two steps"),
                mlp.params(),
                &PARAMS_2,
                1e-4,
            );
        });
    }
}

//! The MLP's layout, initialisation, forward pass, column-subset input gradient and Polyak
//! update, against plain loops; its gradients are `core/tests/rl_gradients.rs`'s.

use super::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn layers_tile_the_flat_vector_in_pytorch_order() {
    let mlp = Mlp::zeros(3, &[5, 4], 2);
    let names: Vec<_> = mlp
        .named_parameters()
        .map(|t| (t.name, t.shape, t.data.len()))
        .collect();
    assert_eq!(
        names,
        [
            ("layers.0.weight".to_string(), vec![5, 3], 15),
            ("layers.0.bias".to_string(), vec![5], 5),
            ("layers.1.weight".to_string(), vec![4, 5], 20),
            ("layers.1.bias".to_string(), vec![4], 4),
            ("layers.2.weight".to_string(), vec![2, 4], 8),
            ("layers.2.bias".to_string(), vec![2], 2),
        ]
    );
    assert_eq!(mlp.params().len(), 54);
    assert_eq!(mlp.layers()[2].offset, 15 + 5 + 20 + 4);
}

#[test]
fn init_stays_within_pytorch_bounds_and_fills_them() {
    let mlp = Mlp::new(16, &[64], 1, &mut ChaCha8Rng::seed_from_u64(7));
    for layer in mlp.layers() {
        let bound = 1.0 / (layer.n_in as f32).sqrt();
        let w = layer.weight(mlp.params());
        assert!(w.iter().all(|v| v.abs() <= bound));
        // Uniform on the whole interval, not a narrower one.
        let max = w.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        assert!(
            max > 0.9 * bound,
            "layer {layer:?}: max |w| {max} vs bound {bound}"
        );
    }
    let again = Mlp::new(16, &[64], 1, &mut ChaCha8Rng::seed_from_u64(7));
    assert_eq!(mlp, again, "same seed, same network");
}

#[test]
fn forward_matches_a_naive_loop() {
    let mlp = Mlp::new(7, &[9, 8], 6, &mut ChaCha8Rng::seed_from_u64(1));
    let mut ws = mlp.workspace(10);
    for (k, v) in ws.input_mut().iter_mut().enumerate() {
        *v = (k as f32 * 0.37).sin();
    }
    mlp.forward(&mut ws);
    for sample in 0..10 {
        let mut x: Vec<f32> = ws.input().column(sample).iter().copied().collect();
        for (l, layer) in mlp.layers().iter().enumerate() {
            let (w, b) = (layer.weight(mlp.params()), layer.bias(mlp.params()));
            x = (0..layer.n_out)
                .map(|o| {
                    let z = b[o]
                        + (0..layer.n_in)
                            .map(|i| w[o * layer.n_in + i] * x[i])
                            .sum::<f32>();
                    if l + 1 < mlp.layers().len() {
                        z.max(0.0)
                    } else {
                        z
                    }
                })
                .collect();
        }
        for (o, &want) in x.iter().enumerate() {
            let got = ws.output()[(o, sample)];
            assert!(
                (got - want).abs() < 1e-5,
                "sample {sample} output {o}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn an_input_gradient_on_some_columns_has_the_bits_of_the_whole_batch_pass() {
    kernels::on_every_path(|path| {
        let shapes = [(10, [40, 30], 37), (10, [400, 300], 64), (3, [5, 4], 3)];
        let cases = [false, true]
            .into_iter()
            .flat_map(|layer_norm| shapes.map(|shape| (shape, layer_norm)));
        for ((n_in, hidden, batch), layer_norm) in cases {
            let mlp = Mlp::new(n_in, &hidden, 1, &mut ChaCha8Rng::seed_from_u64(5));
            // Through the layer norms too, which keep what they need per column.
            let mlp = if layer_norm {
                mlp.with_layer_norm()
            } else {
                mlp
            };
            let mut whole = mlp.workspace(batch);
            for (k, v) in whole.input_mut().iter_mut().enumerate() {
                *v = (k as f32 * 0.61).sin();
            }
            mlp.forward(&mut whole);
            for picked in [
                vec![0],
                vec![batch - 1],
                (0..batch).step_by(2).collect::<Vec<_>>(),
                (1..batch).filter(|i| i % 3 != 0).collect(),
            ] {
                // The whole batch's pass with dL/d output zero outside `picked`.
                for (i, g) in whole.output_grad_mut().iter_mut().enumerate() {
                    *g = if picked.contains(&i) {
                        (i as f32 * 0.37).cos()
                    } else {
                        0.0
                    };
                }
                let mut sub = mlp.workspace(batch);
                mlp.backward_input_columns(&whole, &picked, &mut sub);
                mlp.backward_input(&mut whole);
                let bits = |ws: &MlpWorkspace, c: usize| -> Vec<u32> {
                    ws.input_grad()
                        .column(c)
                        .iter()
                        .map(|v| v.to_bits())
                        .collect()
                };
                for (c, &i) in picked.iter().enumerate() {
                    assert_eq!(
                        bits(&sub, c),
                        bits(&whole, i),
                        "{path}: {hidden:?} batch {batch}, layer norm {layer_norm}, sample {i}"
                    );
                }
            }
        }
    });
}

#[test]
fn polyak_update_moves_tau_of_the_way() {
    let online = Mlp::new(2, &[3], 1, &mut ChaCha8Rng::seed_from_u64(1));
    let mut target = Mlp::zeros(2, &[3], 1);
    target.soft_update_from(&online, 0.25);
    for (t, o) in target.params().iter().zip(online.params()) {
        assert!((t - 0.25 * o).abs() < 1e-7);
    }
    target.copy_params_from(&online);
    assert_eq!(target.params(), online.params());
}

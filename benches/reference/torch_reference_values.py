"""Reference values for `core/tests/rl_gradients.rs` and, with `--layer-norm`,
`core/tests/rl_layer_norm.rs`, computed with PyTorch.

Builds the MLP of the test (6 -> 8 -> 7 -> 6, ReLU between, linear output; with `--layer-norm`
a LayerNorm before each hidden ReLU, PyTorch's `Linear -> LayerNorm -> ReLU`) with parameters
from a formula written identically in Rust, runs forward, MSE loss, backward and two Adam steps,
and prints Rust constants to paste beside the test: probes and sums of the parameters for the
plain network, every value for the normed one.

    pip install torch==2.15.0   # CPU is enough
    python3 benches/reference/torch_reference_values.py [--layer-norm]

Formulas (k is the flat index; parameters in `named_parameters()` order, each row-major: every
Linear's weight and bias, then every LayerNorm's weight and bias):
    parameter[k] = 0.5 * sin(1.3 k + 0.1), plus 1 for a LayerNorm's weight (its gain)
    input[k]     = cos(0.5 k)     (batch-major (9, 6))
    target[k]    = sin(0.3 k)     (batch-major (9, 6))
each computed in float64 and rounded to float32.
"""

import math
import sys

import numpy as np
import torch

N_IN, HIDDEN, N_OUT, BATCH = 6, [8, 7], 6, 9
LR = 0.01
# Parameter indices whose gradient and updated value are printed (plus sums over all of them).
PROBE = list(range(0, 167, 11))


class Mlp(torch.nn.Module):
    def __init__(self, sizes, layer_norm=False):
        super().__init__()
        self.layers = torch.nn.ModuleList(torch.nn.Linear(a, b) for a, b in zip(sizes, sizes[1:]))
        norms = (torch.nn.LayerNorm(n) for n in sizes[1:-1]) if layer_norm else ()
        self.norms = torch.nn.ModuleList(norms)

    def forward(self, x):
        for l, layer in enumerate(self.layers[:-1]):
            x = layer(x)
            if self.norms:
                x = self.norms[l](x)
            x = torch.relu(x)
        return self.layers[-1](x)


def formula(n, f):
    return torch.tensor([f(k) for k in range(n)], dtype=torch.float64).float()


def f32(value):
    """The shortest literal that reads back as the same f32 (what clippy asks for)."""
    return str(np.float32(value))


def rust_array(name, values):
    values = [float(v) for v in values]
    body = ", ".join(f32(v) for v in values)
    return f"const {name}: [f32; {len(values)}] = [{body}];"


def main(layer_norm):
    torch.set_default_dtype(torch.float32)
    mlp = Mlp([N_IN, *HIDDEN, N_OUT], layer_norm)
    with torch.no_grad():
        offset = 0
        for name, p in mlp.named_parameters():
            gain = 1.0 if name.startswith("norms.") and name.endswith(".weight") else 0.0
            value = lambda k, at=offset, gain=gain: gain + 0.5 * math.sin(1.3 * (at + k) + 0.1)
            p.copy_(formula(p.numel(), value).view_as(p))
            offset += p.numel()
    assert offset == (167 + 2 * sum(HIDDEN) if layer_norm else 167)

    x = formula(BATCH * N_IN, lambda k: math.cos(0.5 * k)).view(BATCH, N_IN).requires_grad_(True)
    y = formula(BATCH * N_OUT, lambda k: math.sin(0.3 * k)).view(BATCH, N_OUT)
    adam = torch.optim.Adam(mlp.parameters(), lr=LR)

    def flat_grads():
        return torch.cat([p.grad.reshape(-1) for p in mlp.parameters()])

    def flat_params():
        return torch.cat([p.detach().reshape(-1) for p in mlp.parameters()])

    flag = " --layer-norm" if layer_norm else ""
    print(f"// torch {torch.__version__}, benches/reference/torch_reference_values.py{flag}")
    for step in range(2):
        adam.zero_grad()
        x.grad = None
        out = mlp(x)
        loss = torch.nn.functional.mse_loss(out, y)
        loss.backward()
        g = flat_grads()
        print(f"const LOSS_{step}: f32 = {f32(loss.item())};")
        if step == 0:
            print(rust_array("OUTPUT_0", out.detach().reshape(-1)))
            print(rust_array("INPUT_GRAD_0", x.grad.reshape(-1)))
            if layer_norm:
                print(rust_array("GRAD_0", g))
            else:
                print(rust_array("GRAD_0_PROBE", g[PROBE]))
                print(f"const GRAD_0_SUM: f32 = {f32(g.double().sum().item())};")
                print(f"const GRAD_0_ABS_SUM: f32 = {f32(g.double().abs().sum().item())};")
        adam.step()
    p = flat_params()
    if layer_norm:
        print(rust_array("PARAMS_2", p))
        return
    print(rust_array("PARAMS_2_PROBE", p[PROBE]))
    print(f"const PARAMS_2_SUM: f32 = {f32(p.double().sum().item())};")
    print(f"const PARAMS_2_ABS_SUM: f32 = {f32(p.double().abs().sum().item())};")
    print(f"// PROBE = {PROBE}")


if __name__ == "__main__":
    main(layer_norm="--layer-norm" in sys.argv[1:])

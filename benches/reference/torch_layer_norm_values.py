"""Reference values for `core/tests/rl_layer_norm.rs`, computed with PyTorch.

The MLP of `torch_reference_values.py` (6 -> 8 -> 7 -> 6) with a layer norm before each hidden
ReLU, PyTorch's `Linear -> LayerNorm -> ReLU` (the env critic of `critic_layer_norm`): forward,
MSE loss, backward and two Adam steps, printed as Rust constants to paste beside the test.

    pip install torch==2.15.0   # CPU is enough
    python3 benches/reference/torch_layer_norm_values.py

Formulas (k is the flat index over `parameters()`: every Linear's weight and bias, then every
LayerNorm's weight and bias, each row-major):
    parameter[k] = 0.5 * sin(1.3 k + 0.1), plus 1 for a layer norm's weight (its gain)
    input[k]     = cos(0.5 k)     (batch-major (9, 6))
    target[k]    = sin(0.3 k)     (batch-major (9, 6))
each computed in float64 and rounded to float32.
"""

import math

import numpy as np
import torch

N_IN, HIDDEN, N_OUT, BATCH = 6, [8, 7], 6, 9
LR = 0.01


class NormedMlp(torch.nn.Module):
    def __init__(self, sizes):
        super().__init__()
        self.layers = torch.nn.ModuleList(torch.nn.Linear(a, b) for a, b in zip(sizes, sizes[1:]))
        self.norms = torch.nn.ModuleList(torch.nn.LayerNorm(n) for n in sizes[1:-1])

    def forward(self, x):
        for layer, norm in zip(self.layers[:-1], self.norms):
            x = torch.relu(norm(layer(x)))
        return self.layers[-1](x)


def f32(value):
    """The shortest literal that reads back as the same f32 (what clippy asks for)."""
    return str(np.float32(value))


def rust_array(name, values):
    values = [float(v) for v in values]
    body = ", ".join(f32(v) for v in values)
    return f"const {name}: [f32; {len(values)}] = [{body}];"


def main():
    torch.set_default_dtype(torch.float32)
    mlp = NormedMlp([N_IN, *HIDDEN, N_OUT])
    named = list(mlp.named_parameters())
    total = sum(p.numel() for _, p in named)
    assert total == 167 + 2 * (8 + 7), total
    k = 0
    with torch.no_grad():
        for name, p in named:
            gain = 1.0 if name.startswith("norms.") and name.endswith(".weight") else 0.0
            values = [gain + 0.5 * math.sin(1.3 * (k + i) + 0.1) for i in range(p.numel())]
            p.copy_(torch.tensor(values, dtype=torch.float64).float().view_as(p))
            k += p.numel()

    def formula(n, f):
        return torch.tensor([f(i) for i in range(n)], dtype=torch.float64).float()

    x = formula(BATCH * N_IN, lambda i: math.cos(0.5 * i)).view(BATCH, N_IN).requires_grad_(True)
    y = formula(BATCH * N_OUT, lambda i: math.sin(0.3 * i)).view(BATCH, N_OUT)
    adam = torch.optim.Adam(mlp.parameters(), lr=LR)

    def flat_grads():
        return torch.cat([p.grad.reshape(-1) for p in mlp.parameters()])

    def flat_params():
        return torch.cat([p.detach().reshape(-1) for p in mlp.parameters()])

    print(f"// torch {torch.__version__}, benches/reference/torch_layer_norm_values.py")
    for step in range(2):
        adam.zero_grad()
        x.grad = None
        out = mlp(x)
        loss = torch.nn.functional.mse_loss(out, y)
        loss.backward()
        print(f"const LOSS_{step}: f32 = {f32(loss.item())};")
        if step == 0:
            print(rust_array("OUTPUT_0", out.detach().reshape(-1)))
            print(rust_array("INPUT_GRAD_0", x.grad.reshape(-1)))
            print(rust_array("GRAD_0", flat_grads()))
        adam.step()
    print(rust_array("PARAMS_2", flat_params()))


if __name__ == "__main__":
    main()

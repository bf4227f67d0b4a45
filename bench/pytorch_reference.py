#!/usr/bin/python3
"""PyTorch's own speed on cgsr's work, for bench/speed.sh: PAN x2 inference at an LR size in
eager NCHW and channels-last, and the training step of `cgsr train` (batch of LR patches, L2
loss, backward, gradient-norm clipping, Adam) in both layouts.

The network is PAN as cgsr builds it (models/backbones/pan.h): same layers, same module paths.
With --torchscript FILE (a `cgsr export --format torchscript` of PAN x2) the script loads that
file's weights by name and checks that its eager forward equals the exported one, so both sides
time the same network. Prints one JSON object. Uses Debian's python3-torch (/usr/bin/python3).
"""
import argparse
import json
import statistics
import sys
import time

import torch
import torch.nn as nn
import torch.nn.functional as F

SLOPE = 0.2  # models/layers.h kLeakySlope


def conv(cin, cout, k, bias=True):
    return nn.Conv2d(cin, cout, k, padding=k // 2, bias=bias)


class PixelAttention(nn.Module):
    def __init__(self, c):
        super().__init__()
        self.conv = conv(c, c, 1)

    def forward(self, x):
        return x * torch.sigmoid(self.conv(x))


class PAConv(nn.Module):
    def __init__(self, cin, att, cout):
        super().__init__()
        self.k2 = conv(cin, att, 1)
        self.k3 = conv(cin, att, 3, bias=False)
        self.k4 = conv(att, cout, 3, bias=False)

    def forward(self, x):
        return self.k4(self.k3(x) * torch.sigmoid(self.k2(x)))


class ScpaBlock(nn.Module):
    def __init__(self, nf, w):
        super().__init__()
        self.conv1_a = conv(nf, w, 1, bias=False)
        self.conv1_b = conv(nf, w, 1, bias=False)
        self.k1 = conv(w, w, 3, bias=False)
        self.pa_conv = PAConv(w, w, w)
        self.conv3 = conv(2 * w, nf, 1, bias=False)

    def forward(self, x):
        a = F.leaky_relu(self.conv1_a(x), SLOPE)
        b = F.leaky_relu(self.conv1_b(x), SLOPE)
        a = F.leaky_relu(self.k1(a), SLOPE)
        b = F.leaky_relu(self.pa_conv(b), SLOPE)
        return self.conv3(torch.cat([a, b], 1)) + x


class Pan(nn.Module):
    def __init__(self, nf=40, unf=24, blocks=16, width=20, scale=2):
        super().__init__()
        self.scale = scale
        self.conv_first = conv(3, nf, 3)
        self.blocks = nn.ModuleList([ScpaBlock(nf, width) for _ in range(blocks)])
        self.trunk_conv = conv(nf, nf, 3)
        self.upconv1 = conv(nf, unf, 3)
        self.att1 = PixelAttention(unf)
        self.hr_conv1 = conv(unf, unf, 3)
        self.conv_last = conv(unf, 3, 3)

    def forward(self, x):
        fea = self.conv_first(x)
        trunk = fea
        for block in self.blocks:
            trunk = block(trunk)
        fea = self.trunk_conv(trunk) + fea
        fea = self.upconv1(F.interpolate(fea, scale_factor=float(self.scale), mode="nearest"))
        fea = F.leaky_relu(self.att1(fea), SLOPE)
        fea = F.leaky_relu(self.hr_conv1(fea), SLOPE)
        skip = F.interpolate(x, scale_factor=float(self.scale), mode="bilinear", align_corners=False)
        return self.conv_last(fea) + skip


class Network(nn.Module):
    """cgsr's SRNetwork wrapper: parameters live under 'backbone.'."""

    def __init__(self):
        super().__init__()
        self.backbone = Pan()

    def forward(self, x):
        return self.backbone(x)


def median_ms(fn, warmup, runs):
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times)


def load_exported(net, path, width, height):
    """Copies the exported file's weights into `net` by name; returns max |eager - exported|."""
    exported = torch.jit.load(path)
    params = {name.replace("__", "."): t for name, t in exported.named_parameters()}
    state = net.state_dict()
    missing = sorted(set(state) - set(params))
    if missing:
        sys.exit(f"{path}: not an export of PAN x2 (no weights for {missing[:3]}...)")
    with torch.no_grad():
        for name, t in state.items():
            t.copy_(params[name])
        x = torch.rand(1, 3, height, width, generator=torch.Generator().manual_seed(1))
        return (net(x) - exported(x)).abs().max().item()


def inference(net, width, height, layout, warmup, runs):
    fmt = torch.channels_last if layout == "nhwc" else torch.contiguous_format
    model = net.to(memory_format=fmt).eval()
    x = torch.rand(1, 3, height, width).contiguous(memory_format=fmt)
    with torch.no_grad():
        return median_ms(lambda: model(x), warmup, runs)


def training_steps_per_second(layout, batch, patch, steps, warmup, scale=2):
    """Steps per second, and the milliseconds of a step spent in each phase."""
    torch.manual_seed(0)
    fmt = torch.channels_last if layout == "nhwc" else torch.contiguous_format
    model = Network().to(memory_format=fmt).train()
    optimizer = torch.optim.Adam(model.parameters(), lr=1e-3)
    lr = torch.rand(batch, 3, patch, patch).contiguous(memory_format=fmt)
    hr = torch.rand(batch, 3, patch * scale, patch * scale).contiguous(memory_format=fmt)
    phases = {"forward_and_loss": 0.0, "backward": 0.0, "clip": 0.0, "optimizer": 0.0}

    def step(record):
        t = [time.perf_counter()]

        def lap(name):
            now = time.perf_counter()
            if record:
                phases[name] += now - t[0]
            t[0] = now

        out = model(lr)
        loss = F.mse_loss(out, hr)
        lap("forward_and_loss")
        optimizer.zero_grad()
        loss.backward()
        lap("backward")
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        lap("clip")
        optimizer.step()
        lap("optimizer")

    for _ in range(warmup):
        step(False)
    start = time.perf_counter()
    for _ in range(steps):
        step(True)
    rate = steps / (time.perf_counter() - start)
    return rate, {k: 1e3 * v / steps for k, v in phases.items()}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--input", default="320x240", help="LR size WxH for inference")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--warmup", type=int, default=2)
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--batch", type=int, default=4, help="training patches per step")
    p.add_argument("--patch", type=int, default=24, help="LR training patch side")
    p.add_argument("--train-steps", type=int, default=60, help="timed training steps per layout")
    p.add_argument("--torchscript", default="", help="cgsr export of PAN x2 whose weights to use")
    p.add_argument("--only", choices=("inference", "training"), help="time one of the two")
    a = p.parse_args()
    torch.set_num_threads(a.threads)
    width, height = (int(v) for v in a.input.split("x"))
    net = Network().eval()
    result = {"torch": torch.__version__, "threads": a.threads, "input": a.input}
    if a.torchscript:
        result["max_abs_diff_vs_export"] = load_exported(net, a.torchscript, width, height)
    if a.only != "training":
        result["inference_ms"] = {
            layout: inference(net, width, height, layout, a.warmup, a.runs) for layout in ("nchw", "nhwc")
        }
    if a.only == "inference":
        print(json.dumps(result))
        return
    training = {
        layout: training_steps_per_second(layout, a.batch, a.patch, a.train_steps, a.warmup)
        for layout in ("nchw", "nhwc")
    }
    result["train_steps_per_second"] = {layout: rate for layout, (rate, _) in training.items()}
    result["train_ms_per_step"] = {layout: phases for layout, (_, phases) in training.items()}
    result["train"] = {"batch": a.batch, "patch": a.patch, "steps": a.train_steps}
    print(json.dumps(result))


if __name__ == "__main__":
    main()

"""Runs exported cgsr TorchScript files with Python's torch.jit.load, for verification.

    python3 run_torchscript.py JOB.json RESULT.json

JOB.json:    {"models": [{"path": "m.pt", "runs": [{"inputs": [{"name": "lr_color",
                 "shape": [1, 3, 10, 12], "file": "in.f32"}], "output": "out.f32"}]}]}
RESULT.json: {"torch": "1.13.1", "models": [{"path": ..., "error": null,
                 "runs": [{"shape": [...], "file": "out.f32"}]}]}

Tensors are raw little-endian float32 files. Inputs are passed to forward() by name, so the order
in the job does not matter. An error in one model is recorded and the others still run.
"""
import json
import sys

import torch


def read_float32(path, shape):
    data = torch.from_file(path, shared=False, size=int(torch.Size(shape).numel()), dtype=torch.float32)
    return data.reshape(shape)


def run_model(model):
    entry = {"path": model["path"], "error": None, "runs": []}
    try:
        module = torch.jit.load(model["path"], map_location="cpu")
        module.eval()
        for run in model["runs"]:
            kwargs = {i["name"]: read_float32(i["file"], i["shape"]) for i in run["inputs"]}
            with torch.no_grad():
                out = module(**kwargs)
            out = out.contiguous().to(torch.float32)
            with open(run["output"], "wb") as f:
                f.write(out.numpy().tobytes())
            entry["runs"].append({"shape": list(out.shape), "file": run["output"]})
    except Exception as e:  # reported per model, with the message
        entry["error"] = f"{type(e).__name__}: {e}"
    return entry


def main():
    if len(sys.argv) != 3:
        print("usage: run_torchscript.py JOB.json RESULT.json", file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        job = json.load(f)
    result = {"torch": torch.__version__, "models": [run_model(m) for m in job["models"]]}
    with open(sys.argv[2], "w") as f:
        json.dump(result, f)
    return 0


if __name__ == "__main__":
    sys.exit(main())

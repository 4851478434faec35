#!/usr/bin/python3
"""Fits the per-face prior (issue 48, item 2; decisions 87-89) and writes its C++ data.

    face_train.py ROWS OUT.inc [--hidden 32] [--epochs 60] [--patience 6] [--seed 1] [--tiny]
                  [--report R.json]

ROWS:    the prefix `train_corpus faces` wrote: ROWS.train.f32, ROWS.holdout.f32 (float32 rows:
         the 41 features of core/auto/face_features.h, the clean normal in the face's frame,
         the noisy-to-clean angle in radians, the clean face class) and ROWS.cases.tsv.
OUT.inc: C++ data for core/auto/face_prior.cpp: the feature scaling, the network's weights,
         the provenance (commit, row counts, SHA-256 of the tables, torch version), the holdout
         figures per class and probe rows with their outputs, which the C++ evaluation must
         reproduce (tests/core/face_prior_test.cpp).

Method (decision 89): a multilayer perceptron, inputs standardised, two ReLU layers of --hidden,
four outputs: the clean normal in the face's frame (normalised) and the noisy-to-clean angle.
Loss: the angle to the clean normal (sqrt(2 (1 - cos)), robust: about the angle itself) plus
the absolute error of the predicted noise angle. Adam, batches of 1024, the rows of the
"train" shapes only; the epoch kept is the one with the lowest median angle error on the
"holdout" shapes (early stopping after --patience epochs without gain). CPU, one thread,
seeded, deterministic algorithms, oneDNN off, the BLAS run.sh pins (decision 85): the same rows
give the same bytes. --tiny: 4,000 rows and
3 epochs (CI's check that the trainer runs and repeats itself).
"""
import argparse
import hashlib
import json
import os
import subprocess
import sys

import numpy as np
import torch

FEATURES = 41
WIDTH = FEATURES + 5
CLASSES = ["flat", "curved", "crease", "corner"]


def load(path):
    raw = open(path, "rb").read()
    rows = np.frombuffer(raw, dtype=np.float32).reshape(-1, WIDTH)
    return rows, hashlib.sha256(raw).hexdigest()


class Net(torch.nn.Module):
    def __init__(self, hidden):
        super().__init__()
        self.l0 = torch.nn.Linear(FEATURES, hidden)
        self.l1 = torch.nn.Linear(hidden, hidden)
        self.l2 = torch.nn.Linear(hidden, 4)

    def forward(self, x):
        return self.l2(torch.relu(self.l1(torch.relu(self.l0(x)))))


def angles(out, target, power=1.0):
    n = torch.nn.functional.normalize(out[:, :3], dim=1)
    c = (n * target).sum(dim=1).clamp(-1, 1)
    chord = torch.sqrt(2 * (1 - c) + 1e-12)  # the chord: about the angle, robust to outliers
    return chord if power == 1.0 else (chord + 0.02) ** power  # 0.02: about a degree, a bounded gradient at 0


def angle_deg(out, target):
    n = torch.nn.functional.normalize(out[:, :3], dim=1)
    return torch.rad2deg(torch.atan2(torch.linalg.cross(n, target).norm(dim=1), (n * target).sum(dim=1)))


def figures(net, X, rows):
    with torch.no_grad():
        out = net(X)
    target = torch.from_numpy(rows[:, FEATURES:FEATURES + 3].copy())
    err = angle_deg(out, target).numpy()
    noisy = np.degrees(rows[:, FEATURES + 3])
    noise_err = np.abs(np.degrees(out[:, 3].numpy()) - noisy)
    cls = rows[:, FEATURES + 4].astype(int)
    per = {}
    for k, name in enumerate(CLASSES):
        m = cls == k
        if m.any():
            per[name] = {"rows": int(m.sum()), "median_deg": float(np.median(err[m])),
                         "p90_deg": float(np.percentile(err[m], 90)),
                         "noisy_median_deg": float(np.median(noisy[m])), "noisy_p90_deg": float(np.percentile(noisy[m], 90)),
                         "noise_reading_median_abs_err_deg": float(np.median(noise_err[m]))}
    return float(np.median(err)), per


def blas_library():
    """The BLAS this process loaded (run.sh pins the reference one, decision 85)."""
    with open("/proc/self/maps") as f:
        paths = {line.split()[-1] for line in f if "blas" in line.split()[-1]}
    return ",".join(sorted(paths)) or "unknown"


def c_array(name, values, per_line=8):
    vals = ["%.9g" % float(v) for v in np.asarray(values, dtype=np.float32).ravel()]
    lines = [", ".join(vals[i:i + per_line]) for i in range(0, len(vals), per_line)]
    return "constexpr double %s[] = {\n    %s};\n" % (name, ",\n    ".join(lines))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("rows")
    ap.add_argument("out")
    ap.add_argument("--hidden", type=int, default=32)
    ap.add_argument("--epochs", type=int, default=60)
    ap.add_argument("--patience", type=int, default=6)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--tiny", action="store_true")
    ap.add_argument("--loss-power", type=float, default=1.0,
                    help="the loss is chord^p: 1 (default) about the angle; below 1 seeks a mode (one side of a crease)")
    ap.add_argument("--report")
    a = ap.parse_args()
    torch.manual_seed(a.seed)
    torch.use_deterministic_algorithms(True)
    torch.set_num_threads(1)
    torch.backends.mkldnn.enabled = False  # oneDNN picks its kernels by CPU; the BLAS path does not
    train, train_sha = load(a.rows + ".train.f32")
    hold, hold_sha = load(a.rows + ".holdout.f32")
    if a.tiny:
        train, hold, a.epochs = train[:4000], hold[:1000], 3
    if len(train) == 0 or len(hold) == 0:
        sys.exit("face_train.py: no training or no holdout rows in " + a.rows)
    mean = train[:, :FEATURES].mean(axis=0)
    scale = train[:, :FEATURES].std(axis=0)
    scale[scale < 1e-6] = 1.0
    mean, scale = mean.astype(np.float32), scale.astype(np.float32)
    Xt = torch.from_numpy((train[:, :FEATURES] - mean) / scale)
    Yt = torch.from_numpy(train[:, FEATURES:FEATURES + 4].copy())
    Xh = torch.from_numpy((hold[:, :FEATURES] - mean) / scale)
    net = Net(a.hidden)
    opt = torch.optim.Adam(net.parameters(), lr=3e-3)
    sched = torch.optim.lr_scheduler.StepLR(opt, step_size=15, gamma=0.5)
    gen = torch.Generator().manual_seed(a.seed)
    best, best_state, best_epoch, since = float("inf"), None, -1, 0
    for epoch in range(a.epochs):
        perm = torch.randperm(len(Xt), generator=gen)
        net.train()
        for i in range(0, len(perm), 1024):
            idx = perm[i:i + 1024]
            out = net(Xt[idx])
            loss = angles(out, Yt[idx, :3], a.loss_power).mean() + (out[:, 3] - Yt[idx, 3]).abs().mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
        sched.step()
        net.eval()
        med, _ = figures(net, Xh, hold)
        print("epoch %d: holdout median angle error %.3f deg" % (epoch, med), flush=True)
        if med < best:
            best, best_epoch, since = med, epoch, 0
            best_state = {k: v.clone() for k, v in net.state_dict().items()}
        else:
            since += 1
            if since >= a.patience:
                break
    net.load_state_dict(best_state)
    net.eval()
    med, per = figures(net, Xh, hold)
    tmed, tper = figures(net, Xt, train)
    # Probes: holdout rows spread over the table, in the order of the table.
    probe_idx = np.linspace(0, len(hold) - 1, 6).astype(int)
    with torch.no_grad():
        probe_out = net(torch.from_numpy((hold[probe_idx, :FEATURES] - mean) / scale)).numpy()
    W = {k: v.numpy() for k, v in net.state_dict().items()}
    digest = hashlib.sha256(b"".join(np.asarray(W[k], dtype=np.float32).tobytes() for k in sorted(W))).hexdigest()
    try:
        commit = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], capture_output=True, text=True,
                                cwd=os.path.dirname(os.path.abspath(__file__))).stdout.strip() or "unknown"
    except OSError:
        commit = "unknown"
    version = "face-mlp-%d-h%d-%s" % (len(train), a.hidden, digest[:6])
    lines = ["// Generated by tools/train/face_train.py; do not edit (decision 89). Rebuild it with the",
             "// command in tools/train/README.md; the same rows give the same bytes.",
             "// Holdout figures (rows of holdout-split shapes; angle to the clean normal, degrees):"]
    for name, f in per.items():
        lines.append("//   %-7s %6d rows: prior median %.2f, p90 %.2f; noisy normal median %.2f, p90 %.2f; "
                     "noise reading median |error| %.2f" % (name, f["rows"], f["median_deg"], f["p90_deg"],
                                                            f["noisy_median_deg"], f["noisy_p90_deg"],
                                                            f["noise_reading_median_abs_err_deg"]))
    lines.append("//   all: median %.3f (training rows: %.3f); epoch kept %d" % (med, tmed, best_epoch))
    text = "\n".join(lines) + "\nnamespace face_model_data {\n"
    text += 'constexpr const char* kVersion = "%s";\n' % version
    text += 'constexpr const char* kCommit = "%s";\n' % commit
    text += 'constexpr const char* kTorch = "%s";\n' % torch.__version__
    text += 'constexpr const char* kBlas = "%s";\n' % blas_library()
    text += 'constexpr const char* kTrainSha256 = "%s";\n' % train_sha
    text += 'constexpr const char* kHoldoutSha256 = "%s";\n' % hold_sha
    text += "constexpr long kTrainRows = %d;\nconstexpr long kHoldoutRows = %d;\n" % (len(train), len(hold))
    text += "constexpr int kInputs = %d;\nconstexpr int kHidden = %d;\n" % (FEATURES, a.hidden)
    text += c_array("kMean", mean) + c_array("kScale", scale)
    text += c_array("kW0", W["l0.weight"]) + c_array("kB0", W["l0.bias"])
    text += c_array("kW1", W["l1.weight"]) + c_array("kB1", W["l1.bias"])
    text += c_array("kW2", W["l2.weight"]) + c_array("kB2", W["l2.bias"])
    text += "constexpr int kProbeCount = %d;\n" % len(probe_idx)
    text += c_array("kProbeInputs", hold[probe_idx, :FEATURES]) + c_array("kProbeOutputs", probe_out)
    text += "}  // namespace face_model_data\n"
    with open(a.out, "w") as f:
        f.write(text)
    report = {"version": version, "commit": commit, "torch": torch.__version__, "blas": blas_library(), "train_rows": len(train),
              "holdout_rows": len(hold), "hidden": a.hidden, "epoch": best_epoch, "holdout_median_deg": med,
              "holdout": per, "train_median_deg": tmed, "train": tper}
    if a.report:
        with open(a.report, "w") as f:
            json.dump(report, f, indent=1)
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()

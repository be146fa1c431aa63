"""Int8 weights for the exported pose model (owner: model).

    python3 -m training quantize [--model IN.onnx] [--out OUT.onnx] [--no-check]
    python3 -m training quantize --measure [--split val|test] [--max-clips N] [--rounds R]

Rewrites an fp32 model of docs/model-contract.md so that ONNX Runtime runs its weight matrices in
int8, with the activations quantised on the fly (dynamic quantisation: nothing to calibrate):

- a MatMul whose second input is a float weight initializer of rank 2 (both sides at least
  MIN_WEIGHT_DIM) becomes com.microsoft DynamicQuantizeMatMul with int8 weights and one
  symmetric scale per output column; a following Add of a bias initializer is folded into it;
- an LSTM becomes com.microsoft DynamicQuantizeLSTM: W and R stored transposed as that operator
  wants them ([directions, input, 4H] and [directions, H, 4H]), int8, one symmetric scale per
  gate row (per channel), zero points 0.

Symmetric: the scale of a column is max |w| / 127 and the zero point 0, so every weight is
reproduced within half a scale step and a zero weight stays exactly zero. Inputs, outputs,
shapes and metadata stay those of the contract; `mocap.precision` becomes "int8" and the model
name says so. Everything else stays float32: the geometry of a complete graph (contract 1/2:
mirror averaging, normalisation, rotations), or nothing at all for the network alone (contract
3, `export --geometry engine`), whose geometry the engine does.

The file is written as a temporary beside OUT, checked against the fp32 model through the real
ONNX Runtime (training/ort.py: the engine's `mocapctl infer`) on procedural clips, and only then
moved over OUT: a failed check (QuantizeCheckError, exit 1) leaves the previous file in place.

--measure compares the int8 file (OUT) with the fp32 one (IN) on prepared CMU clips the way the
engine runs them (one character, one frame per call, state carried), and times fp32, the fp16
file beside it and int8 taking turns on one thread; training/results/int8.md holds what it showed.
"""
from __future__ import annotations

import os
import statistics
from pathlib import Path

import numpy as np

from . import onnx_metadata
from .cli import NON_NEGATIVE_INT, POSITIVE_INT
from .errors import CommandError, UsageError

REPO = Path(__file__).resolve().parents[1]
MODELS = REPO / "Packages" / "com.mocap.imu" / "Runtime" / "Models"
DEFAULT_MODEL = MODELS / "mocap_pose_fp32.onnx"
DEFAULT_OUT = MODELS / "mocap_pose_int8.onnx"
CONTRIB_DOMAIN = "com.microsoft"
QMAX = 127   # symmetric int8: -127..127, so that -w and w quantise to opposite values
# Smaller constant matrices are the graph's geometry (the 3x3 mirror of the mirror averaging),
# not learned weights: quantising them, and the rotations they multiply, would only add error.
MIN_WEIGHT_DIM = 16
# Largest accepted max |int8 - fp32| of joint_rotations (matrix entries) on the check's
# procedural clips, whole clip and streamed. The shipped model moves by at most 0.012 (streamed)
# and 0.016 (whole clip); 0.05 leaves a 3x margin and still catches a wrong weight layout, which
# moves them by O(1).
CHECK_TOLERANCE = 0.05
CHECKED_OUTPUT = "joint_rotations"
QUANTIZED_OPS = ("MatMul", "LSTM")
# The shipped int8 file holds the network alone, the engine doing its geometry (results/int8.md).
SHIPPED_CONTRACT = "3"


class QuantizeCheckError(CommandError):
    """The int8 model does not reproduce the fp32 one within CHECK_TOLERANCE (nothing installed)."""


# ------------------------------------------------------------------------------ weights
def symmetric_int8(w: np.ndarray, axis: int) -> tuple:
    """w quantised to int8 with one scale per slice along every axis but `axis` (the axis summed
    over by the product): q = round(w / s), s = max |w| / 127 over `axis`. Returns (q int8 of w's
    shape, s float32 with `axis` removed). A slice of zeros gets scale 1 (its q is 0 anyway)."""
    w = np.asarray(w, dtype=np.float32)
    if not np.all(np.isfinite(w)):
        raise CommandError("a weight holds NaN or inf: nothing to quantise")
    peak = np.max(np.abs(w), axis=axis)
    scale = np.where(peak > 0, peak / QMAX, 1.0).astype(np.float32)
    q = np.rint(w / np.expand_dims(scale, axis))
    return np.clip(q, -QMAX, QMAX).astype(np.int8), scale


def dequantize(q: np.ndarray, scale: np.ndarray, axis: int) -> np.ndarray:
    """The float weights q stands for: q * scale, the scale broadcast along `axis`."""
    return q.astype(np.float32) * np.expand_dims(scale, axis)


# ------------------------------------------------------------------------------ graph rewrite
def _consumers(graph) -> dict:
    uses: dict = {}
    for node in graph.node:
        for name in node.input:
            if name:
                uses.setdefault(name, []).append(node)
    return uses


def _is_weight(arr) -> bool:
    return (arr is not None and arr.dtype == np.float32 and arr.ndim == 2
            and min(arr.shape) >= MIN_WEIGHT_DIM)


def _bias_add(node, n_cols, uses, inits, graph_outputs):
    """The Add that only adds a bias of n_cols floats to node's output, or None."""
    out = node.output[0]
    users = uses.get(out, [])
    if out in graph_outputs or len(users) != 1 or users[0].op_type != "Add" or users[0].domain:
        return None
    add = users[0]
    other = [n for n in add.input if n != out]
    if len(other) != 1 or len(add.input) != 2:
        return None
    bias = inits.get(other[0])
    if bias is None or bias.dtype != np.float32 or bias.shape != (n_cols,):
        return None
    return add, other[0]


def quantize_model(model, ops=QUANTIZED_OPS) -> tuple:
    """An fp32 contract model -> (int8 model, summary), quantising the nodes of the op types in
    `ops` ("MatMul", "LSTM"). The input ModelProto is not changed.
    summary: matmuls, lstms (nodes rewritten), int8_values, float_values_left (weights of the
    rewritten nodes only count once)."""
    import copy
    import onnx
    from onnx import helper, numpy_helper

    meta = onnx_metadata.read(model)
    precision = meta.get("mocap.precision")
    if precision != "fp32":
        raise UsageError(f"the model's mocap.precision is {precision!r}: quantise the fp32 model "
                         f"(its weights are initializers there), e.g. {DEFAULT_MODEL.name}")
    model = copy.deepcopy(model)
    g = model.graph
    inits = {i.name: numpy_helper.to_array(i) for i in g.initializer}
    uses = _consumers(g)
    graph_outputs = {o.name for o in g.output}
    added, folded_adds, new_nodes = {}, set(), []
    summary = {"matmuls": 0, "lstms": 0, "int8_values": 0}

    def add_init(arr, name, weight=False):
        if name not in added:      # a weight two nodes share is stored once
            added[name] = numpy_helper.from_array(arr, name)
            summary["int8_values"] += arr.size if weight else 0
        return name

    for node in g.node:
        if node.op_type == "Add" and node.output[0] in folded_adds:
            continue
        if node.op_type not in ops or node.domain:
            new_nodes.append(node)
        elif node.op_type == "MatMul" and _is_weight(inits.get(node.input[1])):
            w = inits[node.input[1]]
            q, scale = symmetric_int8(w, axis=0)          # one scale per output column
            base = node.input[1]
            ins = [node.input[0], add_init(q, base + "_int8", True), add_init(scale, base + "_scale")]
            out = node.output[0]
            fused = _bias_add(node, w.shape[1], uses, inits, graph_outputs)
            if fused is not None:
                add, bias = fused
                ins += ["", bias]                         # no zero point: symmetric
                out = add.output[0]
                folded_adds.add(out)
            new_nodes.append(helper.make_node("DynamicQuantizeMatMul", ins, [out], name=node.name + "_int8",
                                              domain=CONTRIB_DOMAIN))
            summary["matmuls"] += 1
        elif node.op_type == "LSTM":
            new_nodes.append(_quantized_lstm(node, inits, add_init))
            summary["lstms"] += 1
        else:
            new_nodes.append(node)
    if not summary["matmuls"] and not summary["lstms"]:
        raise UsageError(f"the model has no {' and no '.join(ops)} with a weight matrix: nothing to quantise")
    del g.node[:]
    g.node.extend(new_nodes)
    g.initializer.extend(added.values())
    used = {name for n in g.node for name in n.input}
    kept = [i for i in g.initializer if i.name in used]
    del g.initializer[:]
    g.initializer.extend(kept)
    produced = {name for n in g.node for name in n.output} | {i.name for i in g.input}
    live_info = [v for v in g.value_info if v.name in produced]
    del g.value_info[:]
    g.value_info.extend(live_info)
    if not any(o.domain == CONTRIB_DOMAIN for o in model.opset_import):
        model.opset_import.append(helper.make_opsetid(CONTRIB_DOMAIN, 1))
    meta["mocap.precision"] = "int8"
    meta["mocap.model_name"] = _int8_name(meta.get("mocap.model_name", ""), summary)
    onnx_metadata.replace(model, meta)
    onnx.checker.check_model(model)
    summary["float_values_left"] = int(sum(np.prod(i.dims) for i in g.initializer
                                           if i.data_type == onnx.TensorProto.FLOAT))
    return model, summary


def _int8_name(name: str, summary: dict) -> str:
    # the engine keeps 127 bytes of the name: shorten the source name rather than lose the suffix
    suffix = ", int8 weights" if summary["matmuls"] else ", int8 LSTM weights"
    return name[:127 - len(suffix)] + suffix


def _quantized_lstm(node, inits, add_init):
    from onnx import helper
    attrs = {a.name: helper.get_attribute_value(a) for a in node.attribute}
    if attrs.pop("layout", 0) != 0:
        raise UsageError(f"LSTM {node.name}: layout=1 (batch first) has no quantised form; export with "
                         f"the default layout")
    ins = list(node.input) + [""] * (8 - len(node.input))
    x, w_name, r_name, b, seq, h0, c0, p = ins[:8]
    w, r = inits.get(w_name), inits.get(r_name)
    if w is None or r is None or w.dtype != np.float32 or r.dtype != np.float32 or w.ndim != 3 or r.ndim != 3:
        raise UsageError(f"LSTM {node.name}: W and R must be float32 initializers to quantise")
    # DynamicQuantizeLSTM multiplies X [.., input] by W [dir, input, 4H]: the transpose of the
    # ONNX LSTM's [dir, 4H, input], gate order (i, o, f, c) unchanged. One scale per gate row.
    wq, ws = symmetric_int8(np.transpose(w, (0, 2, 1)), axis=1)
    rq, rs = symmetric_int8(np.transpose(r, (0, 2, 1)), axis=1)
    zero = np.zeros(ws.shape, np.int8)
    inputs = [x, add_init(wq, w_name + "_int8", True), add_init(rq, r_name + "_int8", True), b, seq, h0, c0, p,
              add_init(ws, w_name + "_scale"), add_init(zero, w_name + "_zero"),
              add_init(rs, r_name + "_scale"), add_init(zero.copy(), r_name + "_zero")]
    return helper.make_node("DynamicQuantizeLSTM", inputs, list(node.output), name=node.name + "_int8",
                            domain=CONTRIB_DOMAIN, **attrs)


def load_onnx(path):
    import onnx
    from google.protobuf.message import DecodeError
    path = Path(path)
    try:
        return onnx.load(str(path))
    except (DecodeError, ValueError, RuntimeError) as e:
        raise UsageError(f"{path}: not an ONNX model ({e})") from e


# ------------------------------------------------------------------------------ check
def fixture_inputs(seconds: float = 3.0, seed: int = 0, sensors=None) -> tuple:
    from .export import fixture_inputs as export_fixture
    if sensors is None:
        return export_fixture(seconds=seconds, seed=seed)
    return export_fixture(seconds=seconds, seed=seed, sensors=tuple(sensors))


def _sensor_names(info: dict) -> list:
    order = info["sensor_order"]
    return [n.strip() for n in order.split(",")] if isinstance(order, str) else list(order)


def _check_mask(info: dict, ori) -> "np.ndarray | None":
    """For a model with imu_mask: every sensor present in the first character; the others lack
    the model's optional sensors (inputs zero, as the engine feeds a missing one)."""
    if not info.get("imu_mask"):
        return None
    mask = np.ones(ori.shape[:3], np.float32)
    optional = [k for k, name in enumerate(_sensor_names(info)) if name in info.get("optional", ())]
    for k in optional:
        mask[1:, :, k] = 0.0
    return mask


def check_against_fp32(fp32_path, int8_path, ori=None, acc=None, stream_frames: int = 60) -> dict:
    """Max |int8 - fp32| per output through ONNX Runtime: the whole clip in one call ("whole"),
    and its first stream_frames frames streamed one frame per call as the engine runs them
    ("stream"; fp32 streamed equals fp32 whole to float rounding, training/README.md)."""
    from . import ort
    from .export import OUTPUT_NAMES
    info = ort.model_info(fp32_path)
    if ori is None:
        ori, acc = fixture_inputs(sensors=_sensor_names(info))
    mask = _check_mask(info, ori)
    if mask is not None:
        ori = np.where(mask[..., None, None] > 0, ori, 0.0).astype(np.float32)
        acc = np.where(mask[..., None] > 0, acc, 0.0).astype(np.float32)
    n = min(stream_frames, ori.shape[1])
    m = None if mask is None else mask[:, :n]
    pairs = {"whole": (ort.run_onnx(fp32_path, ori, acc, mask=mask),
                       ort.run_onnx(int8_path, ori, acc, mask=mask)),
             "stream": (ort.run_onnx(fp32_path, ori[:, :n], acc[:, :n], mask=m),
                        ort.run_onnx(int8_path, ori[:, :n], acc[:, :n], stream=True, mask=m))}
    return {tag: {k: float(np.max(np.abs(q[k] - ref[k]))) for k in OUTPUT_NAMES}
            for tag, (ref, q) in pairs.items()}


def check_failures(report: dict) -> list:
    out = []
    for tag in ("whole", "stream"):
        diff = report[tag][CHECKED_OUTPUT]
        if not diff <= CHECK_TOLERANCE:   # NaN fails too
            out.append(f"{tag} {CHECKED_OUTPUT} differ by {diff:.3g} > {CHECK_TOLERANCE:g}")
    return out


def quantize_file(src=DEFAULT_MODEL, dst=DEFAULT_OUT, check: bool = True, ops=QUANTIZED_OPS) -> dict:
    """src (fp32) -> dst (int8): written as a temporary beside dst, checked against src through
    ONNX Runtime (check and the runtime available), then moved over dst."""
    import onnx
    from .files import same_file
    src, dst = Path(src), Path(dst)
    if same_file(src, dst):
        raise UsageError(f"--out {dst} is the model to quantise: choose another file")
    model, summary = quantize_model(load_onnx(src), ops)
    dst.parent.mkdir(parents=True, exist_ok=True)
    tmp = dst.with_name(f".{dst.name}.{os.getpid()}.tmp.onnx")
    info = {"model": str(src), "out": str(dst), **summary, "fp32_bytes": src.stat().st_size}
    try:
        onnx.save(model, str(tmp))
        info["int8_bytes"] = tmp.stat().st_size
        if check:
            from . import ort
            if ort.onnx_runtime_available():
                info["check"] = check_against_fp32(src, tmp)
                failed = check_failures(info["check"])
                if failed:
                    raise QuantizeCheckError("the int8 model does not follow the fp32 one: " + "; ".join(failed)
                                             + f"; nothing written ({dst.name} left as it was)")
            else:
                info["check"] = "skipped: ONNX Runtime not available (scripts/fetch_onnxruntime.sh)"
        else:
            info["check"] = "skipped (--no-check)"
        os.replace(tmp, dst)
    finally:
        tmp.unlink(missing_ok=True)
    return info


# ------------------------------------------------------------------------------ measure
def deviation(reference: list, other: list, clips) -> dict:
    """How far one model's predictions are from another's (evaluate.Prediction lists over the same
    clips): the angle between their local joint rotations (deg) and the distance between their
    root-aligned joint positions on the clip's skeleton (cm), over every joint of every frame:
    mean, 99th percentile and maximum."""
    from .evaluate import root_aligned_positions, rotation_angle_deg
    angles, dists = [], []
    for clip, a, b in zip(clips, reference, other):
        angles.append(rotation_angle_deg(a.local_rot, b.local_rot).ravel())
        _, pa = root_aligned_positions(a.local_rot, clip.offsets)
        _, pb = root_aligned_positions(b.local_rot, clip.offsets)
        dists.append(np.linalg.norm(pa - pb, axis=-1).ravel() * 100.0)
    angles, dists = np.concatenate(angles), np.concatenate(dists)
    return {"angle_mean": float(angles.mean()), "angle_p99": float(np.percentile(angles, 99)),
            "angle_max": float(angles.max()), "pos_mean": float(dists.mean()),
            "pos_p99": float(np.percentile(dists, 99)), "pos_max": float(dists.max())}


def predict_streamed(model_path, clips) -> list:
    """Each clip alone (B = 1), one frame per call, state carried: what the engine does for one
    character. Dynamic quantisation takes its activation ranges per call, so an int8 model's
    answers depend on how frames are grouped into calls; this is the grouping that ships."""
    from .evaluate import Prediction
    from .ort import run_onnx
    out = []
    for c in clips:
        r = run_onnx(model_path, c.imu_orientation[None], c.imu_acceleration[None], stream=True)
        out.append(Prediction(r["joint_rotations"][0].astype(np.float64),
                              r["root_velocity"][0].astype(np.float64)))
    return out


def time_models(models: dict, rounds: int, frames: int = 1800) -> dict:
    """Per-frame time of each model as evaluate's latency row measures it (mocapctl infer
    --stream --threads 1, one character, `frames` frames), the models taking turns `rounds`
    times so that a change of machine load hits them alike: medians over the rounds of the p50
    and of the p99 per call, in microseconds."""
    from .evaluate import measure_latency
    runs = {name: [] for name in models}
    for _ in range(rounds):
        for name, path in models.items():
            runs[name].append(measure_latency(path, frames))
    return {name: {"p50_us": statistics.median(t["p50_us"] for t in ts),
                   "p99_us": statistics.median(t["p99_us"] for t in ts),
                   "load": statistics.median(t["load"] for t in ts)} for name, ts in runs.items()}


METRICS = (("angle_all", "angle (deg)", 2), ("pos", "position (cm)", 2), ("sip", "SIP (deg)", 2),
           ("drift_10s", "10 s drift (m)", 3), ("jitter", "jitter (10^2 m/s^3)", 2))


def measure(fp32_path, int8_path, motions, rounds: int = 5, progress=print) -> dict:
    """fp32 against int8 on prepared motions: accuracy of each (evaluate's metrics, its inputs
    and seed), their deviation from fp32, and the per-frame times of every model given."""
    from .evaluate import Accumulator, predict_onnx, synthesize_clip
    rng = np.random.default_rng(0)            # evaluate's seed and order: the same inputs
    clips = [synthesize_clip(m, rng) for m in motions]
    progress(f"measure: {len(clips)} clips, {sum(c.local_rot.shape[0] for c in clips):,} frames")
    preds = {"fp32": predict_onnx(fp32_path, clips)}
    progress("measure: int8, whole clips in batches (as evaluate runs models)")
    preds["int8 batched"] = predict_onnx(int8_path, clips)
    progress("measure: int8, streamed one frame per call, one character (as the engine runs it)")
    preds["int8 streamed"] = predict_streamed(int8_path, clips)
    scores, devs = {}, {}
    for name, p in preds.items():
        acc = Accumulator()
        for c, pr in zip(clips, p):
            acc.add(c, pr)
        scores[name] = {k: acc.summary()[k] for k, _, _ in METRICS}
        if name != "fp32":
            devs[name] = deviation(preds["fp32"], p, clips)
    return {"clips": len(clips), "frames": int(sum(c.local_rot.shape[0] for c in clips)),
            "scores": scores, "deviation": devs}


def measure_main(args, src: Path, dst: Path) -> int:
    from . import dataset
    from .evaluate import _trim
    for p, opt in ((src, "--model"), (dst, "--out")):
        if not p.is_file():
            raise UsageError(f"{opt} {p}: no such file (--measure compares existing models)")
    motions = _trim(dataset.load_motions(args.split), args.max_clips, 0)
    r = measure(src, dst, motions, rounds=args.rounds)
    print(f"\n{r['clips']} clips of split {args.split}, {r['frames']:,} frames\n")
    print("| model | " + " | ".join(label for _, label, _ in METRICS) + " |")
    print("|---" * (len(METRICS) + 1) + "|")
    for name, s in r["scores"].items():
        print(f"| {name} | " + " | ".join(f"{s[k]:.{d}f}" for k, _, d in METRICS) + " |")
    print("\n| against fp32 | angle mean / p99 / max (deg) | position mean / p99 / max (cm) |\n|---|---|---|")
    for name, d in r["deviation"].items():
        print(f"| {name} | {d['angle_mean']:.3f} / {d['angle_p99']:.2f} / {d['angle_max']:.2f} | "
              f"{d['pos_mean']:.3f} / {d['pos_p99']:.2f} / {d['pos_max']:.2f} |")
    if args.rounds:
        models = {p.name: p for p in (src, src.with_name(src.name.replace("fp32", "fp16")), dst)
                  if p.is_file()}
        t = time_models(models, args.rounds)
        print(f"\nper frame, mocapctl infer --stream --threads 1, medians of {args.rounds} alternating rounds "
              f"({os.cpu_count()} CPUs):\n")
        print("| model | p50 (ms) | p99 (ms) | load average |\n|---|---|---|---|")
        for name, v in t.items():
            print(f"| {name} | {v['p50_us'] / 1000:.3f} | {v['p99_us'] / 1000:.3f} | {v['load']:.1f} |")
    return 0


# ------------------------------------------------------------------------------ CLI
def main(args) -> int:
    src = Path(args.model or DEFAULT_MODEL)
    dst = Path(args.out or DEFAULT_OUT)
    if getattr(args, "measure", False):
        return measure_main(args, src, dst)
    from .files import same_file
    if same_file(dst, DEFAULT_OUT) and src.is_file() and \
            onnx_metadata.read(load_onnx(src)).get("mocap.contract_version") != SHIPPED_CONTRACT:
        raise UsageError(f"{src} is a complete graph; the shipped int8 file is the network alone "
                         f"(model contract {SHIPPED_CONTRACT}): export --checkpoint "
                         f"training/checkpoints/mocap_pose.pt --geometry engine --stride-from {src} "
                         f"--out DIR, then quantize --model DIR/mocap_pose_fp32.onnx (or pass --out "
                         f"elsewhere); nothing written")
    print(f"quantize: {src} -> {dst} ...", flush=True)
    ops = ("LSTM",) if args.float_matmuls else QUANTIZED_OPS
    info = quantize_file(src, dst, check=not args.no_check, ops=ops)
    check = info["check"]
    if isinstance(check, dict):
        check = (f"max |int8 - fp32| {CHECKED_OUTPUT} {check['whole'][CHECKED_OUTPUT]:.4f} whole clip, "
                 f"{check['stream'][CHECKED_OUTPUT]:.4f} streamed (limit {CHECK_TOLERANCE:g})")
    print(f"quantize: {info['matmuls']} MatMul + {info['lstms']} LSTM -> int8 ({info['int8_values']:,} "
          f"weights; {info['float_values_left']:,} float values left), {info['fp32_bytes'] / 1e6:.1f} MB -> "
          f"{info['int8_bytes'] / 1e6:.1f} MB; check: {check}")
    return 0


def add_arguments(parser) -> None:
    parser.add_argument("--model", default=None,
                        help=f"the fp32 model (default {DEFAULT_MODEL.relative_to(REPO)})")
    parser.add_argument("--out", default=None, help=f"the int8 model (default {DEFAULT_OUT.relative_to(REPO)})")
    parser.add_argument("--no-check", dest="no_check", action="store_true",
                        help="install without comparing with the fp32 model through ONNX Runtime")
    parser.add_argument("--float-matmuls", dest="float_matmuls", action="store_true",
                        help="quantise the LSTMs only; the MatMuls (6 %% of the weights, most of the "
                             "int8 model's deviation from fp32) stay float32")
    parser.add_argument("--measure", action="store_true",
                        help="write nothing: compare the existing int8 model (--out) with the fp32 one "
                             "(--model) on prepared CMU clips, streamed as the engine runs it, and time them")
    parser.add_argument("--split", default="val", choices=["train", "val", "test"],
                        help="--measure: the subjects (default val; test only to report)")
    parser.add_argument("--max-clips", dest="max_clips", type=POSITIVE_INT, default=0,
                        help="--measure: the first N clips")
    parser.add_argument("--rounds", type=NON_NEGATIVE_INT, default=5,
                        help="--measure: timing rounds, the models taking turns (0: no timing)")

"""ONNX export of PoseNet per docs/model-contract.md (owner: model).

    python3 -m training export [--checkpoint PATH | --untrained] [--out DIR]

writes DIR/mocap_pose_fp32.onnx and DIR/mocap_pose_fp16.onnx: model contract 1 for a network of
the six default sensors without a mask (the shipped model), contract 2 for a masked network
(ModelConfig.masked: its own sensor list, mocap.sensor_required from its optional sensors, and the
imu_mask input). Both have float32 inputs and
outputs; the fp16 file stores every floating-point initializer as float16 followed by a Cast to
float32 (weight compression only: compute stays float32, which ONNX Runtime's CPU LSTM kernel
requires). Dynamic B and T axes, opset 14, the contract's names and metadata. The files are
validated with onnx.checker and, where ONNX Runtime is available (training/ort.py, the real C
library), compared with PyTorch on procedural fixtures: whole clip and streaming T = 1.

Both files are written as temporaries in DIR, checked, and only then moved over the previous
files (os.replace): an interrupted export or a failed check leaves the previous models in place.
The check fails (ExportCheckError; `python3 -m training export` exits 1) when the maximum
absolute difference of joint_rotations exceeds CHECK_TOLERANCE (fp32 vs PyTorch and fp32
streaming T = 1 vs one whole-clip call: 1e-4; fp16 vs PyTorch: 2e-3, ten times the 2e-4 the
shipped model shows, see training/README.md).
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import torch

from . import onnx_metadata, sensors as se
from . import skeleton as sk
from .errors import CommandError, UsageError
from .model import (ACC_SCALE, ExportWrapper, MaskedExportWrapper, MirrorEnsemble, ModelConfig, NetworkOnly,
                    OUTPUT_SIZE, PoseNet, count_parameters, feature_size, non_finite_tensors)

REPO = Path(__file__).resolve().parents[1]
DEFAULT_OUT = REPO / "Packages" / "com.mocap.imu" / "Runtime" / "Models"
DEFAULT_CHECKPOINT = REPO / "training" / "data" / "checkpoints" / "best.pt"
OPSET = 14
CONTRACT_VERSION = "1"
MASKED_CONTRACT_VERSION = "2"
NETWORK_ONLY_CONTRACT_VERSION = "3"
# Where the geometry runs: "graph" writes the whole model into the file (contract 1 or 2, any
# ONNX runtime can run it); "engine" writes the learned network alone (contract 3) and leaves the
# geometry to the engine, which does it in a few microseconds instead of ~130 graph operators.
GEOMETRIES = ("graph", "engine")
NETWORK_INPUT_NAMES = ["network_input", "state_in_h", "state_in_c"]
NETWORK_OUTPUT_NAMES = ["network_output", "state_out_h", "state_out_c"]
# Metadata a new export takes over from a model file (--stride-from): the stride law is measured
# on the weights (stride-scaling), so the same weights in another form keep it.
STRIDE_KEYS = ("mocap.training_height", "mocap.stride_exponent")
INPUT_NAMES = ["imu_orientation", "imu_acceleration", "state_in_h", "state_in_c"]
MASKED_INPUT_NAMES = ["imu_orientation", "imu_acceleration", "imu_mask", "state_in_h", "state_in_c"]
OUTPUT_NAMES = ["joint_rotations", "root_velocity", "foot_contact", "state_out_h", "state_out_c"]
FP32_NAME = "mocap_pose_fp32.onnx"
FP16_NAME = "mocap_pose_fp16.onnx"
# Largest accepted max |ONNX Runtime - PyTorch| of joint_rotations per file (export check). fp32
# differs by float rounding only (shipped model: 3e-7); fp16 weights move the outputs more
# (shipped model: 1.9e-4 joint_rotations), so 2e-3 leaves a 10x margin and still catches a
# broken conversion. "stream" is the fp32 file streamed T = 1 against one whole-clip call.
CHECK_TOLERANCE = {"fp32": 1e-4, "fp16": 2e-3, "stream": 1e-4}
CHECKED_OUTPUT = "joint_rotations"


class ExportCheckError(CommandError):
    """The exported files do not reproduce PyTorch within CHECK_TOLERANCE (none were installed)."""


def _fmt(x: float) -> str:
    return f"{float(x):.6g}"


def contract_version(net) -> str:
    """The model contract a network exports as: 2 when it takes the mask, else 1."""
    return MASKED_CONTRACT_VERSION if net.config.masked else CONTRACT_VERSION


def contract_metadata(net: PoseNet, precision: str, model_name: str) -> dict:
    require_contract_sensors(net, "the network")
    meta = {
        "mocap.contract_version": contract_version(net),
        "mocap.frame_rate": str(sk.MODEL_FPS),
        "mocap.sensor_order": ",".join(net.config.sensors),
    }
    if net.config.masked:
        meta["mocap.sensor_required"] = ",".join(
            "0" if n in net.config.optional else "1" for n in net.config.sensors)
    return meta | {
        "mocap.joint_names": ",".join(sk.JOINT_NAMES),
        "mocap.joint_parents": ",".join(str(p) for p in sk.PARENTS),
        "mocap.rest_offsets": ",".join(_fmt(v) for v in np.asarray(sk.DEFAULT_OFFSETS).reshape(-1)),
        "mocap.state_layers": str(net.state_layers),
        "mocap.state_size": str(net.state_size),
        "mocap.precision": precision,
        "mocap.model_name": model_name,
        "mocap.wrist_sensor_bone": net.config.wrist_anchor,
    }


def geometry_metadata(net) -> dict:
    """Contract 3's description of the geometry the engine does for a PoseNet or MirrorEnsemble
    (docs/model-contract.md)."""
    from .skeleton import MIRROR_JOINTS
    mirror = isinstance(net, MirrorEnsemble)
    inner = net.net if mirror else net
    n = len(inner.config.sensors)
    anchors = inner.anchor_joints if inner.config.anchored else [0] * n
    meta = {
        "mocap.contract_version": NETWORK_ONLY_CONTRACT_VERSION,
        "mocap.acceleration_scale": _fmt(ACC_SCALE),
        "mocap.anchor_joints": ",".join(str(j) for j in anchors),
        "mocap.masked_features": "1" if inner.config.masked else "0",
        "mocap.mirror_average": "1" if mirror else "0",
    }
    if mirror:
        meta["mocap.mirror_sensors"] = ",".join(str(k) for k in net.mirror_sensors)
        meta["mocap.mirror_joints"] = ",".join(str(j) for j in MIRROR_JOINTS)
    return meta


def export_network_fp32(net, path, model_name: str) -> None:
    """Contract 3: the learned network of net (a PoseNet or MirrorEnsemble) alone."""
    import onnx
    import warnings
    net = net.cpu().eval()
    mirror = isinstance(net, MirrorEnsemble)
    inner = net.net if mirror else net
    core = NetworkOnly(net).eval()
    rows = 2 if mirror else 1
    features = feature_size(len(inner.config.sensors), inner.config.masked)
    x = torch.zeros(rows, 4, features)
    h, c = inner.zero_state(rows)
    dyn = {"network_input": {0: "R", 1: "T"}, "state_in_h": {1: "R"}, "state_in_c": {1: "R"},
           "network_output": {0: "R", 1: "T"}, "state_out_h": {1: "R"}, "state_out_c": {1: "R"}}
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with torch.no_grad(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        torch.onnx.export(core, (x, h, c), str(path), input_names=NETWORK_INPUT_NAMES,
                          output_names=NETWORK_OUTPUT_NAMES, dynamic_axes=dyn, opset_version=OPSET,
                          do_constant_folding=True)
    model = onnx.load(str(path))
    L, H = inner.state_layers, inner.state_size
    _set_shapes(model, {"network_input": ["R", "T", features], "state_in_h": [L, "R", H],
                        "state_in_c": [L, "R", H], "network_output": ["R", "T", OUTPUT_SIZE],
                        "state_out_h": [L, "R", H], "state_out_c": [L, "R", H]})
    onnx_metadata.replace(model, contract_metadata(net, "fp32", model_name) | geometry_metadata(net))
    model.doc_string = "com.mocap.imu pose network, contract version " + NETWORK_ONLY_CONTRACT_VERSION
    onnx.checker.check_model(model)
    onnx.save(model, str(path))


def export_fp32(net: PoseNet, path, model_name: str) -> None:
    import onnx
    net = net.cpu().eval()
    masked = net.config.masked
    wrapper = (MaskedExportWrapper(net) if masked else ExportWrapper(net)).eval()
    b, t, n = 1, 4, len(net.config.sensors)
    ori = torch.eye(3).expand(b, t, n, 3, 3).contiguous()
    acc = torch.zeros(b, t, n, 3)
    h, c = net.zero_state(b)
    dyn = {"imu_orientation": {0: "B", 1: "T"}, "imu_acceleration": {0: "B", 1: "T"},
           "state_in_h": {1: "B"}, "state_in_c": {1: "B"},
           "joint_rotations": {0: "B", 1: "T"}, "root_velocity": {0: "B", 1: "T"},
           "foot_contact": {0: "B", 1: "T"}, "state_out_h": {1: "B"}, "state_out_c": {1: "B"}}
    inputs, input_names = (ori, acc, h, c), INPUT_NAMES
    if masked:
        inputs, input_names = (ori, acc, torch.ones(b, t, n), h, c), MASKED_INPUT_NAMES
        dyn["imu_mask"] = {0: "B", 1: "T"}
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    import warnings
    with torch.no_grad(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        torch.onnx.export(wrapper, inputs, str(path), input_names=input_names,
                          output_names=OUTPUT_NAMES, dynamic_axes=dyn, opset_version=OPSET,
                          do_constant_folding=True)
    model = onnx.load(str(path))
    _fix_state_shapes(model, net)
    onnx_metadata.replace(model, contract_metadata(net, "fp32", model_name))
    model.doc_string = "com.mocap.imu pose model, contract version " + contract_version(net)
    onnx.checker.check_model(model)
    onnx.save(model, str(path))


def _fix_state_shapes(model, net: PoseNet) -> None:
    """Write the contract's shapes on every input and output (symbolic B and T, static rest;
    the exporter leaves some static dims symbolic, e.g. the 24 of a Concat)."""
    L, H, n = net.state_layers, net.state_size, len(net.config.sensors)
    _set_shapes(model, {"imu_orientation": ["B", "T", n, 3, 3], "imu_acceleration": ["B", "T", n, 3],
                        "imu_mask": ["B", "T", n], "state_in_h": [L, "B", H], "state_in_c": [L, "B", H],
                        "joint_rotations": ["B", "T", 24, 3, 3], "root_velocity": ["B", "T", 3],
                        "foot_contact": ["B", "T", 2], "state_out_h": [L, "B", H], "state_out_c": [L, "B", H]})


def _set_shapes(model, shapes: dict) -> None:
    for vi in list(model.graph.input) + list(model.graph.output):
        want = shapes[vi.name]
        shp = vi.type.tensor_type.shape
        del shp.dim[:]
        for d in want:
            dd = shp.dim.add()
            if isinstance(d, str):
                dd.dim_param = d
            else:
                dd.dim_value = d


def convert_fp16(src, dst) -> dict:
    """fp32 ONNX -> fp16 weights: float initializers stored as float16 + Cast to float32."""
    import onnx
    from onnx import helper, numpy_helper, TensorProto
    model = onnx.load(str(src))
    g = model.graph
    casts, new_inits, converted = [], [], 0
    for init in g.initializer:
        if init.data_type != TensorProto.FLOAT:
            new_inits.append(init)
            continue
        arr = numpy_helper.to_array(init)
        half = numpy_helper.from_array(arr.astype(np.float16), init.name + "_fp16")
        new_inits.append(half)
        casts.append(helper.make_node("Cast", [half.name], [init.name], to=TensorProto.FLOAT,
                                      name=init.name + "_cast"))
        converted += arr.size
    del g.initializer[:]
    g.initializer.extend(new_inits)
    nodes = list(g.node)
    del g.node[:]
    g.node.extend(casts + nodes)
    # drop stale value_info of the casted names (they keep float type anyway)
    meta = onnx_metadata.read(model)
    meta["mocap.precision"] = "fp16"
    onnx_metadata.replace(model, meta)
    onnx.checker.check_model(model)
    onnx.save(model, str(dst))
    return {"fp16_values": int(converted)}


def copy_stride_law(src, dst) -> None:
    """dst's metadata takes src's stride law (STRIDE_KEYS); a UsageError when src has none."""
    import onnx
    theirs = onnx_metadata.read(onnx.load(str(src), load_external_data=False))
    missing = [k for k in STRIDE_KEYS if k not in theirs]
    if missing:
        raise UsageError(f"{src} has no {' / '.join(missing)} to take over; nothing written")
    model = onnx.load(str(dst))
    onnx_metadata.replace(model, onnx_metadata.read(model) | {k: theirs[k] for k in STRIDE_KEYS})
    onnx.save(model, str(dst))


def load_checkpoint(path) -> tuple:
    from .train import checkpoint_network, load_checkpoint_file
    ck = load_checkpoint_file(path)
    return checkpoint_network(ck, path).eval(), ck


def untrained_model(seed: int = 0, config: ModelConfig | None = None) -> PoseNet:
    torch.manual_seed(seed)
    return PoseNet(config or ModelConfig()).eval()


# ------------------------------------------------------------------------------ numeric check
def fixture_inputs(seconds: float = 3.0, seed: int = 0, kinds=("walk", "mixed"),
                   sensors=se.DEFAULT_SENSORS) -> tuple:
    """Procedural motions -> synthesised (B,T,N,3,3), (B,T,N,3) float32 (no augmentation) of
    these sensors (segment names)."""
    from . import procedural
    from .synthesis import synthesize
    oris, accs = [], []
    for i, k in enumerate(kinds):
        s = synthesize(procedural.make_motion(k, seconds=seconds, seed=seed + i), sensors=sensors)
        oris.append(s.imu_orientation)
        accs.append(s.imu_acceleration)
    return np.stack(oris).astype(np.float32), np.stack(accs).astype(np.float32)


def fixture_mask(net, ori, acc, seed: int = 0) -> tuple:
    """A mask for fixture inputs of a masked network, and the inputs as the engine feeds them
    with it (a missing sensor's inputs zero): the first character has every sensor; each other
    one lacks its optional sensors for the whole clip and one more non-pelvis sensor for a
    window in the middle. (None, ori, acc) for a network without the mask."""
    if not net.config.masked:
        return None, ori, acc
    sensors = net.config.sensors
    rng = np.random.default_rng(seed)
    b, t, n = ori.shape[:3]
    mask = np.ones((b, t, n), np.float32)
    droppable = [k for k, name in enumerate(sensors) if name != "pelvis" and name not in net.config.optional]
    for i in range(1, b):
        for k, name in enumerate(sensors):
            if name in net.config.optional:
                mask[i, :, k] = 0
        if droppable:
            k = droppable[int(rng.integers(len(droppable)))]
            mask[i, t // 4:(3 * t) // 4, k] = 0
    return mask, ori * mask[..., None, None], acc * mask[..., None]


def torch_outputs(net: PoseNet, ori, acc, mask=None) -> dict:
    with torch.no_grad():
        r, v, c, (h, cc) = net(torch.from_numpy(ori), torch.from_numpy(acc), None,
                               None if mask is None else torch.from_numpy(mask))
    return {"joint_rotations": r.numpy(), "root_velocity": v.numpy(), "foot_contact": c.numpy(),
            "state_out_h": h.numpy(), "state_out_c": cc.numpy()}


def check_against_torch(net: PoseNet, paths: dict, ori=None, acc=None, stream_frames: int = 60,
                        mask=None) -> dict:
    """Max abs difference per output, ONNX Runtime vs PyTorch, for each file; plus the
    difference between streaming (T=1 per call) and one whole-clip call on the fp32 file. A
    masked network runs with a mask (given, else fixture_mask's: sensors missing for whole clips
    and for windows, their inputs zero)."""
    from . import ort
    if ori is None:
        ori, acc = fixture_inputs(sensors=net.config.sensors)
    if mask is None:
        mask, ori, acc = fixture_mask(net, ori, acc)
    ref = torch_outputs(net, ori, acc, mask)
    report = {}
    for tag, p in paths.items():
        out = ort.run_onnx(p, ori, acc, mask=mask)
        report[tag] = {k: float(np.max(np.abs(out[k] - ref[k]))) for k in OUTPUT_NAMES}
    p32 = paths.get("fp32")
    if p32 is not None:
        n = min(stream_frames, ori.shape[1])
        part = None if mask is None else mask[:, :n]
        whole = ort.run_onnx(p32, ori[:, :n], acc[:, :n], mask=part)
        streamed = ort.run_onnx(p32, ori[:, :n], acc[:, :n], stream=True, mask=part)
        report["stream_vs_whole_fp32"] = {k: float(np.max(np.abs(whole[k] - streamed[k])))
                                          for k in OUTPUT_NAMES}
    return report


def check_failures(report: dict) -> list:
    """The entries of a check_against_torch report over CHECK_TOLERANCE, as text."""
    keys = {"fp32": "fp32", "fp16": "fp16", "stream_vs_whole_fp32": "stream"}
    out = []
    for tag, limit_key in keys.items():
        if tag in report:
            diff = report[tag][CHECKED_OUTPUT]
            if not diff <= CHECK_TOLERANCE[limit_key]:   # NaN fails too
                out.append(f"{tag} {CHECKED_OUTPUT} differ by {diff:.3g} > {CHECK_TOLERANCE[limit_key]:g}")
    return out


def require_exportable(net, what: str) -> None:
    """A UsageError for a network the engine cannot run: the contract's state is an LSTM's."""
    if net.config.core != "lstm":
        raise UsageError(f"{what} is a {net.config.core} network (train --size tip, for the architecture "
                         f"comparison); the engine's model contract carries LSTM state only, so it "
                         f"cannot be exported; nothing written")
    require_contract_sensors(net, what)


def require_contract_sensors(net, what: str) -> None:
    """A UsageError for a network without the mask whose sensor list is not contract version 1's
    (the default set in table order): only a masked network exports as contract 2, with its own
    sensor list."""
    if not net.config.masked and tuple(net.config.sensors) != se.DEFAULT_SENSORS:
        raise UsageError(f"{what} reads the sensors {','.join(net.config.sensors)} without a mask input; "
                         f"model contract {CONTRACT_VERSION} has the sensors {','.join(se.DEFAULT_SENSORS)}, "
                         f"and contract {MASKED_CONTRACT_VERSION} (any sensor list) needs a masked network "
                         f"(train --masked, --optional or --sensor-dropout); nothing written")


def export(net: PoseNet, out_dir=DEFAULT_OUT, model_name: str = "mocap-pose", check: bool = True,
           geometry: str = "graph", stride_from=None) -> dict:
    """Write out_dir/FP32_NAME and FP16_NAME: both as temporaries beside them, checked (check and
    ONNX Runtime available), then moved over the previous files. A failed check raises
    ExportCheckError and leaves the previous files untouched. Non-finite weights are refused
    before anything is written: unlike the ONNX Runtime check, this one always runs (--no-check,
    or no ONNX Runtime, would otherwise install a model that outputs NaN). geometry: GEOMETRIES;
    stride_from: a model file whose stride law (STRIDE_KEYS) the new files take over."""
    if geometry not in GEOMETRIES:
        raise UsageError(f"geometry {geometry!r}: expected one of {', '.join(GEOMETRIES)}")
    require_exportable(net, "the network")
    bad = non_finite_tensors(net.state_dict())
    if bad:
        raise ExportCheckError(f"the network's weights hold NaN or inf ({bad}); nothing written")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    p32, p16 = out_dir / FP32_NAME, out_dir / FP16_NAME
    tag = f"{os.getpid()}.tmp.onnx"   # ".onnx" last: tools that look at the suffix still load it
    t32, t16 = out_dir / f".{FP32_NAME}.{tag}", out_dir / f".{FP16_NAME}.{tag}"
    try:
        (export_network_fp32 if geometry == "engine" else export_fp32)(net, t32, model_name)
        if stride_from is not None:
            copy_stride_law(stride_from, t32)
        convert_fp16(t32, t16)
        info = {"fp32": str(p32), "fp16": str(p16), "fp32_bytes": t32.stat().st_size,
                "fp16_bytes": t16.stat().st_size, "parameters": count_parameters(net),
                "state_layers": net.state_layers, "state_size": net.state_size}
        if check:
            from . import ort
            if ort.onnx_runtime_available():
                info["check"] = check_against_torch(net, {"fp32": t32, "fp16": t16})
                failed = check_failures(info["check"])
                if failed:
                    raise ExportCheckError(
                        "ONNX Runtime does not reproduce PyTorch: " + "; ".join(failed)
                        + f"; nothing written ({p32.name} and {p16.name} left as they were)")
            else:
                info["check"] = "skipped: ONNX Runtime not available (scripts/fetch_onnxruntime.sh)"
        os.replace(t32, p32)
        os.replace(t16, p16)
    finally:
        for t in (t32, t16):
            t.unlink(missing_ok=True)
    return info


def main(args) -> int:
    if getattr(args, "geometry", None) == "engine" and not getattr(args, "out", None):
        raise UsageError(f"--geometry engine needs --out: the files in {DEFAULT_OUT.relative_to(REPO)} "
                         "are the complete graphs (contract 1) other runtimes can run; the network "
                         "alone goes to quantize from another folder; nothing written")
    if getattr(args, "untrained", False):
        net = untrained_model(seed=getattr(args, "seed", 0))
        name = "mocap-pose untrained (random init, seed %d)" % getattr(args, "seed", 0)
    else:
        ckpt = Path(getattr(args, "checkpoint", None) or DEFAULT_CHECKPOINT)
        if not ckpt.is_file():
            raise UsageError(f"no checkpoint at {ckpt} (train first; re-export the shipped weights "
                             f"with --checkpoint training/checkpoints/mocap_pose.pt; or pass --untrained)")
        net, ck = load_checkpoint(ckpt)
        require_exportable(net, str(ckpt))
        name = f"mocap-pose lstm{net.state_layers}x{net.state_size}"
        if not getattr(args, "no_mirror", False):
            net = MirrorEnsemble(net).eval()
            name += " mirror-averaged"
        name += checkpoint_label(ck)
    info = export(net, getattr(args, "out", None) or DEFAULT_OUT, model_name=name,
                  check=not getattr(args, "no_check", False),
                  geometry=getattr(args, "geometry", None) or "graph",
                  stride_from=getattr(args, "stride_from", None))
    print(json.dumps(info, indent=1))
    # The height input's stride law belongs to the weights and is measured, not exported.
    if getattr(args, "stride_from", None) is None:
        print("export: these files carry no stride law for the height input yet: python3 -m training "
              "stride-scaling --model FP32 --write FP32 FP16, then quantize (the int8 file copies it); "
              "or take it over from the same weights' earlier file with --stride-from")
    return 0


def checkpoint_label(ck: dict) -> str:
    """Where the weights come from, for the model name: a training step, or an average of
    checkpoints (which has no step of its own)."""
    if ck.get("step") is not None:
        return f" step {ck['step']}"
    sources = ck.get("averaged_from") or []
    if sources:
        return f" average of {len(sources)} checkpoints"
    return ""


def add_arguments(parser) -> None:
    parser.add_argument("--checkpoint", default=None, help=f"checkpoint (default {DEFAULT_CHECKPOINT.relative_to(REPO)})")
    parser.add_argument("--untrained", action="store_true", help="export a seeded random-init model")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default=None, help=f"output folder (default {DEFAULT_OUT.relative_to(REPO)})")
    parser.add_argument("--no-mirror", dest="no_mirror", action="store_true",
                        help="export the single network instead of the mirror-averaged pair "
                             "(model.MirrorEnsemble: ~0.7x the time per frame, larger errors)")
    parser.add_argument("--geometry", choices=GEOMETRIES, default="graph",
                        help="graph: the whole model in the file (contract 1/2, any ONNX runtime); "
                             "engine: the learned network alone (contract 3), the engine doing the "
                             "geometry (faster per frame)")
    parser.add_argument("--stride-from", dest="stride_from", default=None, metavar="MODEL",
                        help="take the stride law (mocap.training_height, mocap.stride_exponent) "
                             "over from this model file of the same weights")
    parser.add_argument("--no-check", dest="no_check", action="store_true",
                        help="skip the ONNX Runtime vs PyTorch comparison")

"""The pose model through the REAL ONNX Runtime: the engine's own C module, driven by
`mocapctl infer` (Packages/com.mocap.imu/Native~/tools/mocapctl/cmd_infer.c).

ONNX Runtime itself (the C library) comes from `scripts/fetch_onnxruntime.sh` into
build/third_party/onnxruntime. mocapctl is built on demand into build/training-engine (CMake,
tests off) unless the environment variable MOCAP_MOCAPCTL names one. Arrays travel through
"tensor bundle" files (format in Packages/com.mocap.imu/Native~/tools/mocapctl/cmd_infer.c and
training/README.md).

    run_onnx(model_path, imu_orientation (B,T,N,3,3), imu_acceleration (B,T,N,3), state=None,
             mask=None (B,T,N), contract 2 only)
        -> dict(joint_rotations (B,T,24,3,3), root_velocity (B,T,3), foot_contact (B,T,2),
                state_out_h (L,B,H), state_out_c (L,B,H))
    onnx_runtime_available() -> bool
"""
from __future__ import annotations

import ctypes
import os
import re
import struct
import subprocess
import tempfile
import threading
from pathlib import Path

import numpy as np

from .sensors import MAX_SENSORS

REPO = Path(__file__).resolve().parent.parent
NATIVE = REPO / "Packages" / "com.mocap.imu" / "Native~"
ORT_DIR = REPO / "build" / "third_party" / "onnxruntime"
ENGINE_BUILD = REPO / "build" / "training-engine"
FETCH_SCRIPT = REPO / "scripts" / "fetch_onnxruntime.sh"

BUNDLE_MAGIC = b"MOCAPTNS"
BUNDLE_VERSION = 1
_NAME = 32


class OnnxRuntimeError(RuntimeError):
    """ONNX Runtime or mocapctl is unavailable, or a model/inference failed."""


# ------------------------------------------------------------------------------------------
# Tensor bundles

def write_bundle(path, tensors: dict) -> None:
    """Write {name: array} as a tensor bundle (float32, little-endian)."""
    with open(path, "wb") as f:
        f.write(BUNDLE_MAGIC + struct.pack("<II", BUNDLE_VERSION, len(tensors)))
        for name, arr in tensors.items():
            a = np.ascontiguousarray(np.asarray(arr, dtype="<f4"))
            raw = name.encode()
            if len(raw) >= _NAME:
                raise ValueError(f"tensor name too long: {name}")
            f.write(raw.ljust(_NAME, b"\0"))
            f.write(struct.pack("<I", a.ndim) + struct.pack(f"<{a.ndim}I", *a.shape))
            f.write(a.tobytes())


def read_bundle(path) -> dict:
    """Read a tensor bundle into {name: float32 array}."""
    data = Path(path).read_bytes()
    if data[:8] != BUNDLE_MAGIC:
        raise OnnxRuntimeError(f"{path} is not a tensor bundle")
    version, count = struct.unpack_from("<II", data, 8)
    if version != BUNDLE_VERSION:
        raise OnnxRuntimeError(f"{path}: bundle version {version}")
    pos, out = 16, {}
    for _ in range(count):
        name = data[pos:pos + _NAME].split(b"\0")[0].decode()
        (rank,) = struct.unpack_from("<I", data, pos + _NAME)
        dims = struct.unpack_from(f"<{rank}I", data, pos + _NAME + 4)
        pos += _NAME + 4 + 4 * rank
        n = int(np.prod(dims)) if rank else 1
        out[name] = np.frombuffer(data, dtype="<f4", count=n, offset=pos).reshape(dims).astype(np.float32)
        pos += 4 * n
    return out


# ------------------------------------------------------------------------------------------
# Locating ONNX Runtime and mocapctl

def onnx_runtime_library() -> Path | None:
    """The libonnxruntime the engine will load (env MOCAP_ONNXRUNTIME_PATH or the fetched one)."""
    env = os.environ.get("MOCAP_ONNXRUNTIME_PATH")
    candidates = [Path(env)] if env else []
    candidates.append(ORT_DIR / "lib" / "libonnxruntime.so")
    for c in candidates:
        if c.is_file():
            return c
    return None


_available: bool | None = None


def onnx_runtime_available() -> bool:
    """True when the real ONNX Runtime library and its headers are present and the library loads
    (ctypes check of OrtGetApiBase; cached). mocapctl is built on first use by run_onnx."""
    global _available
    if _available is None:
        lib = onnx_runtime_library()
        ok = lib is not None and (ORT_DIR / "include" / "onnxruntime_c_api.h").is_file()
        if ok:
            try:
                handle = ctypes.CDLL(str(lib), mode=os.RTLD_LOCAL)
                ok = hasattr(handle, "OrtGetApiBase")
            except OSError:
                ok = False
        _available = ok
    return _available


_build_lock = threading.Lock()
_mocapctl: dict = {}


def _run(cmd, **kw):
    return subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)


def mocapctl_path(require_onnx: bool = True) -> Path:
    """mocapctl: $MOCAP_MOCAPCTL, or built (incrementally) into build/training-engine. With
    require_onnx it must have ONNX Runtime support (infer, model-info); synth/replay do not need
    it. Raises OnnxRuntimeError with the cause."""
    with _build_lock:
        if require_onnx in _mocapctl or (not require_onnx and _mocapctl):
            return _mocapctl.get(require_onnx) or next(iter(_mocapctl.values()))
        env = os.environ.get("MOCAP_MOCAPCTL")
        if env:
            if not Path(env).is_file():
                raise OnnxRuntimeError(f"MOCAP_MOCAPCTL={env} does not exist")
            _mocapctl[require_onnx] = Path(env)
            return Path(env)
        have_headers = (ORT_DIR / "include" / "onnxruntime_c_api.h").is_file()
        if require_onnx and not have_headers:
            raise OnnxRuntimeError(f"ONNX Runtime is not in {ORT_DIR}: run {FETCH_SCRIPT}")
        exe = ENGINE_BUILD / "mocapctl"
        for attempt in range(2):
            if not (ENGINE_BUILD / "CMakeCache.txt").is_file() or attempt == 1:
                r = _run(["cmake", "-S", NATIVE, "-B", ENGINE_BUILD, "-DCMAKE_BUILD_TYPE=Release",
                          "-DMOCAP_BUILD_TESTS=OFF", f"-DMOCAP_ONNXRUNTIME_DIR={ORT_DIR}"])
                if r.returncode != 0:
                    raise OnnxRuntimeError(f"configuring the engine failed:\n{r.stdout}{r.stderr}")
            r = _run(["cmake", "--build", ENGINE_BUILD, "--target", "mocapctl", "-j",
                      str(os.cpu_count() or 2)])
            if r.returncode != 0 or not exe.is_file():
                raise OnnxRuntimeError(f"building mocapctl failed:\n{r.stdout[-3000:]}{r.stderr[-3000:]}")
            # Built with the headers? (A build configured before the fetch lacks them.)
            probe = _run([exe, "model-info", ENGINE_BUILD / "no-such-model.onnx"])
            if not have_headers or "without ONNX Runtime headers" not in probe.stderr:
                _mocapctl[require_onnx] = exe
                return exe
        raise OnnxRuntimeError(f"{exe} was built without ONNX Runtime: {probe.stderr.strip()}")


# ------------------------------------------------------------------------------------------
# Running

def _state_arrays(state):
    if state is None:
        return None, None
    if isinstance(state, dict):
        h = state.get("state_in_h", state.get("state_out_h"))
        c = state.get("state_in_c", state.get("state_out_c"))
        return h, c
    h, c = state
    return h, c


def run_onnx(model_path, imu_orientation, imu_acceleration, state=None, *, frames_per_call=None,
             stream=False, threads=None, timing=False, mask=None):
    """Run an ONNX pose model on the real ONNX Runtime (through `mocapctl infer`).

    imu_orientation (B,T,N,3,3), imu_acceleration (B,T,N,3) in the model's sensor order (N = 6
    for contract 1; mocapctl infer checks N against the model); state: None (zeros), a tuple
    (h, c) or a dict with state_in_h/state_in_c (or a previous result's state_out_h/_c), each
    (L,B,H); mask: imu_mask (B,T,N) of a contract-2 model (None: every sensor present; mocapctl
    refuses one for a model without the mask input). The whole clip runs in one call unless frames_per_call (or stream=True: 1 frame per
    call, as the engine runs). Returns a dict of float32 arrays: joint_rotations (B,T,24,3,3),
    root_velocity (B,T,3), foot_contact (B,T,2), state_out_h, state_out_c (L,B,H); with
    timing=True also "timing": {calls, first_us, p50_us, p99_us, mean_us} per call. threads: ONNX
    Runtime's intra-op threads; None: every core for a whole clip in one call (large products
    that split well: 16 clips ran 1.5x faster on 2 threads), else the engine's default (one)."""
    ori = np.asarray(imu_orientation, dtype=np.float32)
    acc = np.asarray(imu_acceleration, dtype=np.float32)
    if ori.ndim != 5 or ori.shape[3:] != (3, 3) or not 1 <= ori.shape[2] <= MAX_SENSORS:
        raise ValueError(f"imu_orientation must be (B,T,N,3,3) with N 1..{MAX_SENSORS}, got {ori.shape}")
    if acc.shape != ori.shape[:3] + (3,):
        raise ValueError(f"imu_acceleration must be {ori.shape[:3] + (3,)}, got {acc.shape}")
    if mask is not None:
        mask = np.asarray(mask, dtype=np.float32)
        if mask.shape != ori.shape[:3]:
            raise ValueError(f"imu_mask must be {ori.shape[:3]}, got {mask.shape}")
    model_path = Path(model_path)
    if not model_path.is_file():
        raise FileNotFoundError(f"model {model_path} does not exist")
    exe = mocapctl_path()
    tensors = {"imu_orientation": ori, "imu_acceleration": acc}
    if mask is not None:
        tensors["imu_mask"] = mask
    h, c = _state_arrays(state)
    if h is not None:
        tensors["state_in_h"] = h
    if c is not None:
        tensors["state_in_c"] = c
    with tempfile.TemporaryDirectory(prefix="mocap-ort-") as tmp:
        inp, out = Path(tmp) / "in.tensors", Path(tmp) / "out.tensors"
        write_bundle(inp, tensors)
        cmd = [exe, "infer", "--model", model_path, "--input", inp, "--output", out]
        if stream:
            cmd.append("--stream")
        elif frames_per_call:
            cmd += ["--frames", str(int(frames_per_call))]
        if threads is None and not stream and not frames_per_call:
            threads = os.cpu_count() or 1
        if threads:
            cmd += ["--threads", str(int(threads))]
        env = dict(os.environ)
        lib = onnx_runtime_library()
        if lib is not None and "MOCAP_ONNXRUNTIME_PATH" not in env:
            env["MOCAP_ONNXRUNTIME_PATH"] = str(lib)
        r = _run(cmd, env=env)
        if r.returncode != 0:
            raise OnnxRuntimeError(f"mocapctl infer failed ({r.returncode}): {r.stderr.strip()}")
        result = read_bundle(out)
    if timing:
        result["timing"] = parse_timing(r.stdout)
    return result


def parse_timing(text: str) -> dict:
    m = re.search(r"timing: calls (\d+) frames_per_call (\d+) first_us ([\d.]+) p50_us ([\d.]+) "
                  r"p99_us ([\d.]+) mean_us ([\d.]+)", text)
    if not m:
        raise OnnxRuntimeError(f"no timing line in mocapctl output:\n{text}")
    keys = ["calls", "frames_per_call", "first_us", "p50_us", "p99_us", "mean_us"]
    return {k: (int(v) if i < 2 else float(v)) for i, (k, v) in enumerate(zip(keys, m.groups()))}


def model_info(model_path) -> dict:
    """`mocapctl model-info` parsed: model_name, precision, contract_version, frame_rate,
    sensor_order, sensor_count, optional (segment names), imu_mask (bool), state_layers,
    state_size, joint_names, joint_parents, rest_offsets (24,3); training_height and
    stride_exponent when the model has stride scaling."""
    r = _run([mocapctl_path(), "model-info", model_path])
    if r.returncode != 0:
        raise OnnxRuntimeError(r.stderr.strip())
    info = {"joint_names": [], "joint_parents": [], "rest_offsets": []}
    for line in r.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0] in ("model_name", "precision", "contract_version",
                                            "frame_rate", "sensor_order", "sensor_count",
                                            "optional", "imu_mask"):
            info[parts[0]] = " ".join(parts[1:])
        elif parts[:2] == ["stride_scaling", "training_height"]:
            info["training_height"], info["stride_exponent"] = float(parts[2]), float(parts[5])
        elif parts[:1] == ["state"]:
            info["state_layers"], info["state_size"] = int(parts[2].rstrip(",")), int(parts[4])
        elif len(parts) == 6 and parts[0].isdigit():
            info["joint_names"].append(parts[1])
            info["joint_parents"].append(int(parts[2]))
            info["rest_offsets"].append([float(x) for x in parts[3:6]])
    info["rest_offsets"] = np.array(info["rest_offsets"], dtype=np.float32)
    if "frame_rate" in info:
        info["frame_rate"] = float(info["frame_rate"])
    if "sensor_count" in info:
        info["sensor_count"] = int(info["sensor_count"])
    if "optional" in info:
        info["optional"] = [] if info["optional"] == "none" else info["optional"].split(",")
    if "imu_mask" in info:
        info["imu_mask"] = info["imu_mask"] == "yes"
    return info

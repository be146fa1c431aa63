"""The key/value metadata of an ONNX model (ModelProto.metadata_props), for every command that
reads or writes it: export, quantize and stride-scaling. Needs onnx, never torch."""
from __future__ import annotations


def read(model) -> dict:
    """The model's metadata as a dict, in file order."""
    return {p.key: p.value for p in model.metadata_props}


def replace(model, meta: dict) -> None:
    """Makes `meta` the model's whole metadata, in its order."""
    del model.metadata_props[:]
    for k, v in meta.items():
        p = model.metadata_props.add()
        p.key, p.value = k, str(v)


def update(model, values: dict) -> None:
    """Sets `values`, leaving every other key where it was; a new key goes last."""
    values = dict(values)
    for p in model.metadata_props:
        if p.key in values:
            p.value = str(values.pop(p.key))
    for k, v in values.items():
        p = model.metadata_props.add()
        p.key, p.value = k, str(v)

"""onnx_metadata: the key order and values a model's metadata keeps through read, replace and
update (the engine and model-info print the keys in file order)."""
import onnx
from onnx import helper

from training import onnx_metadata


def _model(meta):
    graph = helper.make_graph([helper.make_node("Identity", ["x"], ["y"])], "g",
                              [helper.make_tensor_value_info("x", onnx.TensorProto.FLOAT, [1])],
                              [helper.make_tensor_value_info("y", onnx.TensorProto.FLOAT, [1])])
    model = helper.make_model(graph)
    onnx_metadata.replace(model, meta)
    return model


def test_replace_makes_the_given_keys_the_whole_metadata_in_order():
    model = _model({"b": "1", "a": "2"})
    onnx_metadata.replace(model, {"c": 3, "a": "x"})
    assert list(onnx_metadata.read(model).items()) == [("c", "3"), ("a", "x")]


def test_update_keeps_other_keys_in_place_and_appends_new_ones_once():
    model = _model({"a": "1", "b": "2", "c": "3"})
    onnx_metadata.update(model, {"b": "20", "d": 4.5})
    onnx_metadata.update(model, {"d": "5"})
    assert list(onnx_metadata.read(model).items()) == [("a", "1"), ("b", "20"), ("c", "3"), ("d", "5")]
    round_trip = onnx.load_from_string(model.SerializeToString())
    assert onnx_metadata.read(round_trip) == onnx_metadata.read(model)

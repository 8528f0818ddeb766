#!/usr/bin/python3
"""Writes tiny_segnet.onnx: a 1x1 convolution standing in for a segmentation network in the tests.

Input  'image'  1x3xHxW (RGB, normalized), H and W free.
Output 'scores' 1x4xHxW logits: channel 0 = 'unlabeled' (always 0), 1 = 4*R, 2 = 4*G, 3 = 4*B.
With the card tiny_segnet.yaml (classes [none, road, car, sky]) a red image is road, green car, blue sky.
Run with Debian's /usr/bin/python3 (python3-onnx, python3-numpy): /usr/bin/python3 make_tiny_onnx.py
"""
import os

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

weights = np.zeros((4, 3, 1, 1), dtype=np.float32)
weights[1, 0, 0, 0] = 4.0  # R -> road
weights[2, 1, 0, 0] = 4.0  # G -> car
weights[3, 2, 0, 0] = 4.0  # B -> sky
bias = np.zeros((4,), dtype=np.float32)

graph = helper.make_graph(
    [helper.make_node("Conv", ["image", "w", "b"], ["scores"], kernel_shape=[1, 1])],
    "tiny_segnet",
    [helper.make_tensor_value_info("image", TensorProto.FLOAT, [1, 3, "H", "W"])],
    [helper.make_tensor_value_info("scores", TensorProto.FLOAT, [1, 4, "H", "W"])],
    initializer=[numpy_helper.from_array(weights, "w"), numpy_helper.from_array(bias, "b")],
)
model = helper.make_model(graph, producer_name="semslam-tests", opset_imports=[helper.make_opsetid("", 11)])
model.ir_version = 6
onnx.checker.check_model(model)
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "tiny_segnet.onnx")
onnx.save(model, out)
print(out, os.path.getsize(out), "bytes")

#!/usr/bin/python3
"""A slow, independent NumPy reference of the two segmentation networks semslam builds in C++ (ESPNetv2 s=2.0
and SINet, Cityscapes), for checking the C++ networks against known outputs.

It shares nothing with the C++ code: its own reader of PyTorch state dicts (Python's pickle module with a
whitelist, both the legacy and the zip container), its own float64 layers (convolution with groups and
dilation, batch norm, PReLU, pooling, bilinear resizing, transposed convolution) and the two forward passes
written from the papers and the state dicts' names and shapes.

  /usr/bin/python3 tools/segnet_reference.py --net espnetv2 \
      --weights ../shared/data/segmentation_weights/espnetv2_s_2.0_city_1024x512.pth \
      --image ../shared/data/cityscapes_samples/frankfurt_000000_000294_leftImg8bit.png --step 16 \
      --out tests/semantics/data/espnetv2_expected.json

The input is the image subsampled by taking every `step`-th pixel (no interpolation, so C++ gets the same
pixels), cropped to multiples of the network's divisor, normalized with the ImageNet statistics in RGB order.
The JSON holds the input size, the logits of every channel at a fixed set of output pixels, the argmax class
histogram of the whole output, and (with --truth) the pixel accuracy against a trainId image.
Needs only Debian's python3-numpy (run with /usr/bin/python3); PNG files are read by the small decoder below.
"""
import argparse
import collections
import io
import json
import math
import pickle
import struct
import sys
import zipfile
import zlib

import numpy as np

# ---------------------------------------------------------------------------------------------------------
# State dicts


class _Storage:
    def __init__(self, dtype, key, view_offset=0):
        self.dtype, self.key, self.view_offset = dtype, key, view_offset


class _TensorRef:
    def __init__(self, storage, offset, size, stride):
        self.storage, self.offset, self.size, self.stride = storage, offset, tuple(size), tuple(stride)


_DTYPES = {"FloatStorage": "<f4", "DoubleStorage": "<f8", "HalfStorage": "<f2", "LongStorage": "<i8",
           "IntStorage": "<i4", "ShortStorage": "<i2", "CharStorage": "i1", "ByteStorage": "u1",
           "BoolStorage": "u1"}


def _rebuild_tensor(storage, offset, size, stride, *unused):
    return _TensorRef(storage, offset, size, stride)


class _Unpickler(pickle.Unpickler):
    def find_class(self, module, name):
        if module == "collections" and name == "OrderedDict":
            return collections.OrderedDict
        if module == "torch._utils" and name in ("_rebuild_tensor_v2", "_rebuild_tensor"):
            return _rebuild_tensor
        if module == "torch._utils" and name == "_rebuild_parameter":
            return lambda data, *unused: data
        if module == "torch" and name in _DTYPES:
            return name
        raise pickle.UnpicklingError("unsupported global %s.%s" % (module, name))

    def persistent_load(self, pid):
        assert pid[0] == "storage"
        view_offset = pid[5][1] if len(pid) > 5 and pid[5] is not None else 0
        return _Storage(_DTYPES[pid[1]], pid[2], view_offset)


def _materialize(ref, raw):
    data = np.frombuffer(raw, dtype=ref.storage.dtype)
    itemsize = data.itemsize
    view = np.lib.stride_tricks.as_strided(
        data[ref.storage.view_offset + ref.offset:], shape=ref.size,
        strides=tuple(s * itemsize for s in ref.stride))
    return np.array(view, dtype=np.float64 if data.dtype.kind == "f" else np.int64)


def load_state_dict(path):
    with open(path, "rb") as f:
        blob = f.read()
    if blob[:4] == b"PK\x03\x04":
        z = zipfile.ZipFile(io.BytesIO(blob))
        pkl = [n for n in z.namelist() if n.endswith("data.pkl")][0]
        prefix = pkl[:-len("data.pkl")]
        root = _Unpickler(io.BytesIO(z.read(pkl))).load()
        raw = lambda key: z.read(prefix + "data/" + key)
    else:
        f = io.BytesIO(blob)
        for _ in range(3):  # magic number, protocol version, system information
            pickle.load(f)
        root = _Unpickler(f).load()
        keys = pickle.load(f)
        dtype_of = {}
        for v in root.values():
            if isinstance(v, _TensorRef):
                dtype_of[v.storage.key] = np.dtype(v.storage.dtype)
        storages = {}
        for key in keys:
            (n,) = struct.unpack("<q", f.read(8))
            storages[key] = f.read(n * dtype_of[key].itemsize)
        raw = lambda key: storages[key]
    return {k: _materialize(v, raw(v.storage.key)) for k, v in root.items() if isinstance(v, _TensorRef)}


# ---------------------------------------------------------------------------------------------------------
# PNG (8-bit grey, grey+alpha, RGB, RGBA; not interlaced), returned as H x W (x C) uint8 in the file's order.


def read_png(path):
    with open(path, "rb") as f:
        blob = f.read()
    assert blob[:8] == b"\x89PNG\r\n\x1a\n", path + ": not a PNG file"
    pos, idat, header = 8, [], None
    while pos < len(blob):
        (length,) = struct.unpack(">I", blob[pos:pos + 4])
        kind, data = blob[pos + 4:pos + 8], blob[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", data)
        elif kind == b"IDAT":
            idat.append(data)
    width, height, depth, color, _, _, interlace = header
    assert depth == 8 and interlace == 0 and color in (0, 2, 4, 6), path + ": unsupported PNG layout"
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[color]
    stride = width * channels
    raw = zlib.decompress(b"".join(idat))
    out = bytearray(height * stride)
    prev = bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)]
        row = bytearray(line)
        if kind == 1:
            for x in range(channels, stride):
                row[x] = (row[x] + row[x - channels]) & 255
        elif kind == 2:
            row = bytearray((a + b) & 255 for a, b in zip(line, prev))
        elif kind == 3:
            for x in range(stride):
                left = row[x - channels] if x >= channels else 0
                row[x] = (line[x] + ((left + prev[x]) >> 1)) & 255
        elif kind == 4:
            for x in range(stride):
                a = row[x - channels] if x >= channels else 0
                b = prev[x]
                c = prev[x - channels] if x >= channels else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                row[x] = (line[x] + (a if pa <= pb and pa <= pc else (b if pb <= pc else c))) & 255
        elif kind != 0:
            raise ValueError(path + ": bad PNG filter")
        out[y * stride:(y + 1) * stride] = row
        prev = row
    img = np.frombuffer(bytes(out), dtype=np.uint8)
    return img.reshape(height, width) if channels == 1 else img.reshape(height, width, channels)


def resize_nearest(labels, height, width):
    # OpenCV's INTER_NEAREST: destination pixel i takes source floor(i * src / dst).
    rows = np.minimum((np.arange(height) * labels.shape[0] / height).astype(int), labels.shape[0] - 1)
    cols = np.minimum((np.arange(width) * labels.shape[1] / width).astype(int), labels.shape[1] - 1)
    return labels[rows][:, cols]


# ---------------------------------------------------------------------------------------------------------
# Layers on C x H x W float64 arrays


def conv2d(x, w, stride=1, pad=(0, 0), dilation=1, groups=1, bias=None):
    c, h, wd = x.shape
    o, cg, kh, kw = w.shape
    assert cg * groups == c, (x.shape, w.shape, groups)
    ph, pw = pad if isinstance(pad, tuple) else (pad, pad)
    xp = np.pad(x, ((0, 0), (ph, ph), (pw, pw)))
    eh, ew = (kh - 1) * dilation + 1, (kw - 1) * dilation + 1
    win = np.lib.stride_tricks.sliding_window_view(xp, (eh, ew), axis=(1, 2))
    win = win[:, ::stride, ::stride, ::dilation, ::dilation]  # C, Ho, Wo, kh, kw
    og = o // groups
    out = np.empty((o, win.shape[1], win.shape[2]))
    for g in range(groups):
        out[g * og:(g + 1) * og] = np.einsum("chwij,ocij->ohw", win[g * cg:(g + 1) * cg],
                                             w[g * og:(g + 1) * og], optimize=True)
    if bias is not None:
        out += bias[:, None, None]
    return out


def batch_norm(x, sd, prefix, eps):
    scale = sd[prefix + ".weight"] / np.sqrt(sd[prefix + ".running_var"] + eps)
    return (x - sd[prefix + ".running_mean"][:, None, None]) * scale[:, None, None] + sd[prefix + ".bias"][:, None, None]


def prelu(x, slope):
    return np.where(x >= 0, x, x * slope.reshape(-1, *([1] * (x.ndim - 1))))


def avg_pool(x, k, stride, pad=0):
    # count_include_pad=True, floor rounding (PyTorch's defaults).
    c, h, w = x.shape
    xp = np.pad(x, ((0, 0), (pad, pad), (pad, pad)))
    win = np.lib.stride_tricks.sliding_window_view(xp, (k, k), axis=(1, 2))[:, ::stride, ::stride]
    return win.mean(axis=(3, 4))


def _adaptive_bounds(n_in, n_out):
    return [(math.floor(i * n_in / n_out), math.ceil((i + 1) * n_in / n_out)) for i in range(n_out)]


def adaptive_avg_pool(x, out_h, out_w):
    c, h, w = x.shape
    out = np.empty((c, out_h, out_w))
    for i, (y0, y1) in enumerate(_adaptive_bounds(h, out_h)):
        for j, (x0, x1) in enumerate(_adaptive_bounds(w, out_w)):
            out[:, i, j] = x[:, y0:y1, x0:x1].mean(axis=(1, 2))
    return out


def _bilinear_taps(n_in, n_out, align_corners):
    taps = []
    for i in range(n_out):
        if align_corners:
            src = i * (n_in - 1) / (n_out - 1) if n_out > 1 else 0.0
        else:
            src = max((i + 0.5) * n_in / n_out - 0.5, 0.0)
        i0 = min(int(math.floor(src)), n_in - 1)
        i1 = min(i0 + 1, n_in - 1)
        taps.append((i0, i1, src - i0))
    return taps


def bilinear(x, out_h, out_w, align_corners):
    rows = _bilinear_taps(x.shape[1], out_h, align_corners)
    cols = _bilinear_taps(x.shape[2], out_w, align_corners)
    r0 = np.array([t[0] for t in rows]); r1 = np.array([t[1] for t in rows]); fr = np.array([t[2] for t in rows])
    c0 = np.array([t[0] for t in cols]); c1 = np.array([t[1] for t in cols]); fc = np.array([t[2] for t in cols])
    top = x[:, r0][:, :, c0] * (1 - fc) + x[:, r0][:, :, c1] * fc
    bottom = x[:, r1][:, :, c0] * (1 - fc) + x[:, r1][:, :, c1] * fc
    return top * (1 - fr)[:, None] + bottom * fr[:, None]


def channel_shuffle(x, groups):
    c, h, w = x.shape
    return x.reshape(groups, c // groups, h, w).transpose(1, 0, 2, 3).reshape(c, h, w)


def softmax_max(x):
    e = np.exp(x - x.max(axis=0, keepdims=True))
    return (e / e.sum(axis=0, keepdims=True)).max(axis=0, keepdims=True)


# ---------------------------------------------------------------------------------------------------------
# ESPNetv2 (Mehta et al., CVPR 2019), s = 2.0, Cityscapes: 20 output channels at the input size.

ESP_EPS = 1e-5


def esp_cbr(sd, p, x, stride=1, groups=1, dilation=1):
    w = sd[p + ".conv.weight"]
    x = conv2d(x, w, stride, (w.shape[2] // 2) * dilation, dilation, groups)
    return prelu(batch_norm(x, sd, p + ".bn", ESP_EPS), sd[p + ".act.weight"])


def esp_cb(sd, p, x, groups=1):
    return batch_norm(conv2d(x, sd[p + ".conv.weight"], 1, 0, 1, groups), sd, p + ".bn", ESP_EPS)


def esp_br(sd, p, x):
    return prelu(batch_norm(x, sd, p + ".bn", ESP_EPS), sd[p + ".act.weight"])


def eesp(sd, p, x, stride, dilations, downsample):
    k = len(dilations)
    reduced = esp_cbr(sd, p + ".proj_1x1", x, groups=k)
    branches = []
    for i, d in enumerate(dilations):
        w = sd["%s.spp_dw.%d.conv.weight" % (p, i)]
        b = conv2d(reduced, w, stride, d, d, reduced.shape[0])
        branches.append(b if i == 0 else b + branches[-1])  # hierarchical feature fusion
    merged = esp_br(sd, p + ".br_after_cat", np.concatenate(branches))
    expanded = esp_cb(sd, p + ".conv_1x1_exp", merged, groups=k)
    if downsample:
        return expanded
    if expanded.shape == x.shape:
        expanded = expanded + x
    return prelu(expanded, sd[p + ".module_act.weight"])


def esp_downsampler(sd, p, x, image, dilations):
    pooled = avg_pool(x, 3, 2, 1)
    out = np.concatenate([pooled, eesp(sd, p + ".eesp", x, 2, dilations, True)])
    while image.shape[1] != pooled.shape[1]:
        image = avg_pool(image, 3, 2, 1)
    reinforced = esp_cb(sd, p + ".inp_reinf.1", esp_cbr(sd, p + ".inp_reinf.0", image))
    return prelu(out + reinforced, sd[p + ".act.weight"])


def cbr_seq(sd, p, x, groups=1):
    w = sd[p + ".cbr.0.weight"]
    x = conv2d(x, w, 1, w.shape[2] // 2, 1, groups)
    return prelu(batch_norm(x, sd, p + ".cbr.1", ESP_EPS), sd[p + ".cbr.2.weight"])


def pyramid_pool(sd, p, x, last):
    x = cbr_seq(sd, p + ".projection_layer", x)
    h, w = x.shape[1:]
    outs = []
    for i, s in enumerate([2.0, 1.5, 1.0, 0.5, 0.1]):
        hs, ws = max(int(math.ceil(h * s)), 5), max(int(math.ceil(w * s)), 5)
        kernel = sd["%s.stages.%d.weight" % (p, i)]
        dw = lambda t: conv2d(t, kernel, 1, 1, 1, t.shape[0])
        if s < 1.0:
            o = bilinear(dw(adaptive_avg_pool(x, hs, ws)), h, w, True)
        elif s > 1.0:
            o = adaptive_avg_pool(dw(bilinear(x, hs, ws, True)), h, w)
        else:
            o = dw(x)
        outs.append(o)
    o = np.concatenate(outs)
    o = prelu(batch_norm(o, sd, p + ".merge_layer.0.br.0", ESP_EPS), sd[p + ".merge_layer.0.br.1.weight"])
    o = channel_shuffle(o, 5)
    o = cbr_seq(sd, p + ".merge_layer.2", o, groups=o.shape[0] // 5)
    o = conv2d(o, sd[p + ".merge_layer.3.weight"], bias=sd.get(p + ".merge_layer.3.bias"))
    if last:
        return o
    return prelu(batch_norm(o, sd, p + ".br.br.0", ESP_EPS), sd[p + ".br.br.1.weight"])


def efficient_pw(sd, p, x):
    gate = 1.0 / (1.0 + np.exp(-conv2d(x.mean(axis=(1, 2), keepdims=True), sd[p + ".wt_layer.1.weight"])))
    w = sd[p + ".expansion_layer.cbr.0.weight"]
    return cbr_seq(sd, p + ".expansion_layer", x, groups=x.shape[0] // w.shape[1]) * gate


def espnetv2(sd, image):
    b = "base_net."
    l1 = esp_cbr(sd, b + "level1", image, stride=2)
    l2 = esp_downsampler(sd, b + "level2_0", l1, image, [1, 2, 3, 4])
    l3 = esp_downsampler(sd, b + "level3_0", l2, image, [1, 2, 3, 4])
    for i in range(3):
        l3 = eesp(sd, "%slevel3.%d" % (b, i), l3, 1, [1, 2, 3, 4], False)
    l4 = esp_downsampler(sd, b + "level4_0", l3, image, [1, 2, 3, 4])
    for i in range(7):
        l4 = eesp(sd, "%slevel4.%d" % (b, i), l4, 1, [1, 1, 2, 3], False)
    up = lambda t: bilinear(t, 2 * t.shape[1], 2 * t.shape[2], True)
    d = pyramid_pool(sd, "bu_dec_l1", l4, False)
    d = up(d) + efficient_pw(sd, "merge_enc_dec_l2", l3)
    d = pyramid_pool(sd, "bu_dec_l2", prelu(batch_norm(d, sd, "bu_br_l2.0", ESP_EPS), sd["bu_br_l2.1.weight"]), False)
    d = up(d) + efficient_pw(sd, "merge_enc_dec_l3", l2)
    d = pyramid_pool(sd, "bu_dec_l3", prelu(batch_norm(d, sd, "bu_br_l3.0", ESP_EPS), sd["bu_br_l3.1.weight"]), False)
    d = up(d) + efficient_pw(sd, "merge_enc_dec_l4", l1)
    d = pyramid_pool(sd, "bu_dec_l4", prelu(batch_norm(d, sd, "bu_br_l4.0", ESP_EPS), sd["bu_br_l4.1.weight"]), True)
    return bilinear(d, image.shape[1], image.shape[2], True)


# ---------------------------------------------------------------------------------------------------------
# SINet (Park et al. 2019), Cityscapes: 19 output channels at half the input size.

SI_EPS = 1e-3
# Per block of level3 (3) and level4 (10): (kernel, pooling) of its two branches; pooling 0 = a plain 3x3
# depthwise convolution, 1 = a separable k x 1 + 1 x k pair at full resolution, n > 1 = the pair after n x n
# average pooling, upsampled back.
SI_CONFIG = [[(3, 1), (5, 1)], [(3, 0), (3, 1)], [(3, 0), (3, 1)],
             [(3, 1), (5, 1)], [(3, 0), (3, 1)], [(5, 1), (5, 4)], [(3, 2), (5, 8)], [(3, 1), (5, 1)],
             [(3, 1), (5, 1)], [(3, 0), (3, 1)], [(5, 1), (5, 8)], [(3, 2), (5, 4)], [(3, 0), (5, 2)]]


def si_bn(sd, p, x):
    return batch_norm(x, sd, p, SI_EPS)


def si_se_separable(sd, p, x, stride):
    # depthwise 3x3 -> squeeze block (global average, dense layers with PReLU, channel scaling) -> 1x1 -> BN -> PReLU
    x = conv2d(x, sd[p + ".conv.0.weight"], stride, 1, 1, x.shape[0])
    s = x.mean(axis=(1, 2))
    i = 0
    while "%s.conv.1.dense.%d.weight" % (p, i) in sd:
        s = sd["%s.conv.1.dense.%d.weight" % (p, i)] @ s + sd["%s.conv.1.dense.%d.bias" % (p, i)]
        s = prelu(s, sd["%s.conv.1.dense.%d.weight" % (p, i + 1)])
        i += 2
    x = x * s[:, None, None]
    x = conv2d(x, sd[p + ".conv.2.weight"])
    return prelu(si_bn(sd, p + ".bn", x), sd[p + ".act.weight"])


def si_branch(sd, p, x, kernel, pool):
    if pool == 0:
        y = si_bn(sd, p + ".conv.1", conv2d(x, sd[p + ".conv.0.weight"], 1, 1, 1, x.shape[0]))
    else:
        if pool > 1:
            x = avg_pool(x, pool, pool)
        r = kernel // 2
        y = (si_bn(sd, p + ".B_v", conv2d(x, sd[p + ".vertical.weight"], 1, (r, 0), 1, x.shape[0])) +
             si_bn(sd, p + ".B_h", conv2d(x, sd[p + ".horizontal.weight"], 1, (0, r), 1, x.shape[0])))
    y = conv2d(prelu(y, sd[p + ".act_conv1x1.0.weight"]), sd[p + ".act_conv1x1.1.weight"])
    if pool > 1:
        y = bilinear(y, y.shape[1] * pool, y.shape[2] * pool, True)
    return si_bn(sd, p + ".bn", y)


def si_module(sd, p, x, config, residual):
    reduced = channel_shuffle(conv2d(x, sd[p + ".c1.conv.weight"], groups=2), 2)
    out = np.concatenate([si_branch(sd, "%s.d%d" % (p, i + 1), reduced, k, a) for i, (k, a) in enumerate(config)])
    if residual:
        out = out + x
    return prelu(si_bn(sd, p + ".BR.bn", out), sd[p + ".BR.act.weight"])


def si_br(sd, p, x):
    return prelu(si_bn(sd, p + ".bn", x), sd[p + ".act.weight"])


def sinet(sd, image):
    e = "encoder."
    w = sd[e + "level1.conv.weight"]
    l1 = prelu(si_bn(sd, e + "level1.bn", conv2d(image, w, 2, 1)), sd[e + "level1.act.weight"])
    l2 = si_se_separable(sd, e + "level2_0", l1, 2)
    l3_0 = si_se_separable(sd, e + "level3_0", l2, 2)
    l3 = l3_0
    for i in range(3):
        l3 = si_module(sd, "%slevel3.%d" % (e, i), l3, SI_CONFIG[i], i > 0)
    l4_0 = si_se_separable(sd, e + "level4_0", si_br(sd, e + "BR3", np.concatenate([l3_0, l3])), 2)
    l4 = l4_0
    for i in range(10):
        l4 = si_module(sd, "%slevel4.%d" % (e, i), l4, SI_CONFIG[3 + i], i not in (0, 5))
    coarse = conv2d(si_br(sd, e + "BR4", np.concatenate([l4_0, l4])), sd[e + "classifier.conv.weight"])
    up = lambda t: bilinear(t, 2 * t.shape[1], 2 * t.shape[2], False)
    stage1 = si_bn(sd, "bn_4", up(coarse))
    l3c = sd["level3_C.conv.weight"]
    side = prelu(si_bn(sd, "level3_C.bn", conv2d(l3, l3c)), sd["level3_C.act.weight"])
    stage2 = si_bn(sd, "bn_3", up(side * (1 - softmax_max(stage1)) + stage1))
    stage3 = l2 * (1 - softmax_max(stage2)) + stage2
    # Transposed 2x2 convolution with stride 2: every input pixel writes a 2x2 block.
    wt = sd["classifier.weight"]  # in, out, 2, 2
    c, h, wd = stage3.shape
    out = np.zeros((wt.shape[1], 2 * h, 2 * wd))
    for i in range(2):
        for j in range(2):
            out[:, i::2, j::2] = np.einsum("chw,co->ohw", stage3, wt[:, :, i, j])
    return out


# ---------------------------------------------------------------------------------------------------------

NETS = {"espnetv2": (espnetv2, 32), "sinet": (sinet, 128)}
MEAN = np.array([0.485, 0.456, 0.406])
STD = np.array([0.229, 0.224, 0.225])


def prepare(image_rgb, step, divisor):
    if image_rgb.ndim == 2:
        image_rgb = np.repeat(image_rgb[:, :, None], 3, axis=2)
    sub = image_rgb[::step, ::step, :3]
    h, w = sub.shape[0] // divisor * divisor, sub.shape[1] // divisor * divisor
    sub = sub[:h, :w]
    rgb = sub.astype(np.float64) / 255.0
    return ((rgb - MEAN) / STD).transpose(2, 0, 1)


def sample_pixels(h, w, n=24):
    # A fixed spread of output pixels: a 6 x 4 grid inset from the borders, plus the corners.
    ys = [int(round((i + 0.5) * h / 4)) for i in range(4)]
    xs = [int(round((j + 0.5) * w / 6)) for j in range(6)]
    pts = [(y, x) for y in ys for x in xs][:n]
    return pts + [(0, 0), (0, w - 1), (h - 1, 0), (h - 1, w - 1)]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--net", choices=sorted(NETS), required=True)
    ap.add_argument("--weights", required=True)
    ap.add_argument("--image", required=True)
    ap.add_argument("--step", type=int, default=16, help="take every step-th pixel of the image")
    ap.add_argument("--truth", help="trainId image (any size: compared after nearest-neighbour resizing)")
    ap.add_argument("--out", help="JSON file (default: stdout)")
    args = ap.parse_args()

    forward, divisor = NETS[args.net]
    sd = load_state_dict(args.weights)
    image = read_png(args.image)
    x = prepare(image, args.step, divisor)
    logits = forward(sd, x)
    c, h, w = logits.shape
    labels = logits[:19].argmax(axis=0)
    hist = np.bincount(labels.ravel(), minlength=19)
    result = {
        "net": args.net, "image": args.image.split("/")[-1], "step": args.step,
        "input_height": x.shape[1], "input_width": x.shape[2],
        "output_channels": c, "output_height": h, "output_width": w,
        "class_histogram": [int(v) for v in hist],
        "samples": [{"y": y, "x": xx, "logits": [round(float(v), 5) for v in logits[:, y, xx]]}
                    for (y, xx) in sample_pixels(h, w)],
    }
    if args.truth:
        truth = read_png(args.truth)
        pred = resize_nearest(labels, truth.shape[0], truth.shape[1])
        valid = truth < 19
        result["pixel_accuracy"] = float((pred[valid] == truth[valid]).mean())
    text = json.dumps(result, indent=1) + "\n"
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()

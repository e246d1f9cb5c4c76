#!/usr/bin/env python3
"""The tokenizer's training step in PyTorch (Python): the peer of bench_tat.

A line-by-line re-implementation of the NEC tokenizer (nec-rvq / nec-vq) of
tat/src/tokenizer.cpp, quantizer.cpp, fk.cpp and loss.cpp: the same modules
created in the same order (so the same torch.manual_seed gives the same
initial weights), the same forward, the same losses, and the step of
TatTrainer::step (zero_grad, backward, the gradient clip, AdamW at the scheduled
learning rate) on the synthetic batch of benchmarks/bench_tat.cpp, drawn with
the same torch random calls. Linear layers compute as LibTorch's do
(peer_layers.Linear). Its first two losses therefore equal bench_tat's
counters loss_step0 / loss_step1 up to float rounding, which scripts/bench.sh
checks.

    /usr/bin/python3 benchmarks/peer_tat_step.py --expect-parameters N [--joints 22 100] [--threads 1 2]
        [--configs DIR]   # tat_cpu.json and owo_cpu.json, as bench_tat --configs=DIR
        [--profile-ops DIR]   # one more step per setting under the op profiler, as bench_tat --profile_ops=DIR

Prints one JSON object on stdout (per setting: wall-clock and process CPU
time per step in ms over the repetitions, the first losses, parameter count,
peak memory of a step); exits 1 when the parameter count differs from
--expect-parameters (the count bench_tat reports). Runs with nec's allocator
policy and shares its measurement with the other peers (peer_step.py).
"""
import argparse
import json
import math
import os
import sys

import torch
import torch.nn as nn
import torch.nn.functional as F

from peer_layers import Linear
from peer_step import add_arguments, keep_large_allocations_in_heap, print_json, run_settings, ScheduledTrainee

SEED = 0                 # torch.manual_seed before inputs and model, as bench_tat
RESIDUAL_DILATION = 3    # tokenizer.cpp kResidualDilation
FEED_FORWARD_MULT = 2    # tokenizer.cpp kFeedForwardMult
MASKED_SCORE = -1e9      # tokenizer.cpp kMaskedScore
LAPLACE_EPSILON = 1e-5   # quantizer.cpp kLaplaceEpsilon
TINY_SQUARED_NORM = 1e-20  # fk.cpp kTinySquaredNorm
ROOT_MOTION_SCALE = 20.0  # model_space.h kRootMotionScale
YAW_RATE_SCALE = 60.0     # model_space.h kYawRateScale
MODEL_CHANNELS = 10       # model_space.h kModelChannels


# ---- Configuration (defaults of tat/include/nec/tat/{training,tokenizer,quantizer,loss}.h) ----

def read_config(configs):
    with open(os.path.join(configs, "tat_cpu.json")) as f:
        raw = json.load(f)
    with open(os.path.join(configs, "owo_cpu.json")) as f:
        embedding_dim = json.load(f)["encoder"]["dim"]
    model = raw.get("model", {})
    quantizer = model.get("quantizer", {})
    loss = raw.get("loss", {})
    optimizer = raw.get("optimizer", {})
    kind = model.get("kind", "nec-rvq")
    if kind not in ("nec-rvq", "nec-vq"):
        sys.exit(f"peer_tat_step: model.kind {kind!r} is not re-implemented (nec-rvq, nec-vq only)")
    return {
        "joint_embedding_dim": embedding_dim,
        "dim": model.get("dim", 128),
        "blocks": model.get("blocks", 2),
        "attention_layers": model.get("attention_layers", 1),
        "heads": model.get("heads", 4),
        "layers": quantizer.get("layers", 4),
        "codebook_size": quantizer.get("codebook_size", 256),
        "code_dim": quantizer.get("code_dim", 128),
        "ema_decay": quantizer.get("ema_decay", 0.99),
        "commitment_weight": quantizer.get("commitment_weight", 0.02),
        "dead_code_threshold": quantizer.get("dead_code_threshold", 1.0),
        "quantize_dropout": quantizer.get("quantize_dropout", 0.2),
        "loss": {k: loss.get(k, d) for k, d in (("rotation", 1.0), ("root", 0.02), ("position", 0.0),
                                                ("velocity", 0.0), ("vertical", 0.08),
                                                ("positions_from_step", 0))},
        "learning_rate": optimizer.get("learning_rate", 2e-4),
        "final_lr_fraction": optimizer.get("final_lr_fraction", 0.1),
        "warmup_steps": optimizer.get("warmup_steps", 200),
        "weight_decay": optimizer.get("weight_decay", 0.0),
        "grad_clip": optimizer.get("grad_clip", 1.0),
        "steps": raw.get("steps", 4000),
        "batch_size": raw.get("batch_size", 32),
        "window_frames": raw.get("data", {}).get("window_frames", 64),
    }


# ---- Tokenizer (tokenizer.cpp) ----

def rest_pose_features():
    """(MODEL_CHANNELS): zero root motion, identity rot6D."""
    rest = torch.zeros(MODEL_CHANNELS)
    rest[3] = 1.0
    rest[7] = 1.0
    return rest


class ResidualUnit(nn.Module):
    """x + pointwise(ReLU(dilated(ReLU(x)))); (N, D, T) -> (N, D, T)."""

    def __init__(self, dim):
        super().__init__()
        self.dilated = nn.Conv1d(dim, dim, 3, padding=RESIDUAL_DILATION, dilation=RESIDUAL_DILATION)
        self.pointwise = nn.Conv1d(dim, dim, 1)

    def forward(self, x):
        return x + self.pointwise(torch.relu(self.dilated(torch.relu(x))))


class DownBlock(nn.Module):
    """Conv (k4, s2, p1) + ResNet1D; (N, D, T) -> (N, D, T / 2)."""

    def __init__(self, dim):
        super().__init__()
        self.conv = nn.Conv1d(dim, dim, 4, stride=2, padding=1)
        self.residual = ResidualUnit(dim)

    def forward(self, x):
        return self.residual(self.conv(x))


class UpBlock(nn.Module):
    """Nearest x2, conv (k3, p1) + ResNet1D; (N, D, T) -> (N, D, 2 T)."""

    def __init__(self, dim):
        super().__init__()
        self.conv = nn.Conv1d(dim, dim, 3, padding=1)
        self.residual = ResidualUnit(dim)

    def forward(self, x):
        n, d, t = x.shape
        repeated = x.unsqueeze(-1).expand(n, d, t, 2).reshape(n, d, 2 * t)
        return self.residual(self.conv(repeated))


class SpatialAttention(nn.Module):
    """Pre-norm transformer layer over the tokens of each time step."""

    def __init__(self, dim, heads):
        super().__init__()
        self.heads = heads
        self.attention_norm = nn.LayerNorm(dim)
        self.qkv = Linear(dim, 3 * dim)
        self.out = Linear(dim, dim)
        self.ffn_norm = nn.LayerNorm(dim)
        self.ffn_in = Linear(dim, FEED_FORWARD_MULT * dim)
        self.ffn_out = Linear(FEED_FORWARD_MULT * dim, dim)

    def forward(self, x, key_bias, first_token_only=False):
        """x (B, T, N, D); key_bias (B, 1, 1, 1, N) -> (B, T, N or 1, D)."""
        b, t, n, d = x.shape
        head_dim = d // self.heads
        queries = 1 if first_token_only else n
        normalized = self.attention_norm(x)
        qkv = self.qkv(normalized).view(b, t, n, 3, self.heads, head_dim).permute(3, 0, 1, 4, 2, 5)
        query = qkv[0].narrow(3, 0, queries) * (1.0 / math.sqrt(head_dim))
        scores = torch.matmul(query, qkv[1].transpose(-1, -2)) + key_bias  # (B, T, H, Q, N)
        mixed = torch.matmul(torch.softmax(scores, -1), qkv[2])           # (B, T, H, Q, Dh)
        attended = x.narrow(2, 0, queries) + self.out(mixed.permute(0, 1, 3, 2, 4).reshape(b, t, queries, d))
        return attended + self.ffn_out(F.gelu(self.ffn_in(self.ffn_norm(attended))))


def per_token(block, tokens):
    """A temporal block on every token sequence: (B, T, N, D) -> (B, T', N, D)."""
    b, t, n, d = tokens.shape
    out = block(tokens.permute(0, 2, 3, 1).reshape(b * n, d, t))
    return out.view(b, n, d, out.size(2)).permute(0, 3, 1, 2).contiguous()


def key_bias(joint_mask):
    """(B, J) bool -> (B, 1, 1, 1, 1 + J) additive key bias; token 0 never masked."""
    keep = torch.cat([torch.ones(joint_mask.size(0), 1, dtype=joint_mask.dtype), joint_mask], 1)
    bias = torch.zeros(keep.shape).masked_fill_(keep.logical_not(), MASKED_SCORE)
    return bias.view(keep.size(0), 1, 1, 1, keep.size(1))


def root_rise(model):
    """(B, T, N, MODEL_CHANNELS), joint 0 the root -> (B, T, 1, 1): y_t - y_(t-1) scaled as the path, frame 0's 0."""
    height = model[:, :, :1, 1:2]
    return F.pad(height[:, 1:] - height[:, :-1], (0, 0, 0, 0, 1, 0)) * ROOT_MOTION_SCALE


def decoder_attention_bias(joint_mask):
    """(B, J) bool -> (B, 1, 1, 1 + J, 1 + J): the joints read every real token, the virtual joint only itself."""
    n = joint_mask.size(1) + 1
    bias = key_bias(joint_mask).expand(joint_mask.size(0), 1, 1, n, n).clone()
    bias[:, :, :, 0, 1:] = MASKED_SCORE
    return bias


class NecEncoder(nn.Module):
    def __init__(self, c):
        super().__init__()
        d = c["dim"]
        self.input = nn.Sequential(Linear(MODEL_CHANNELS, d), nn.ReLU(), Linear(d, d))  # built in this order, as tokenizer.cpp
        self.embedding = Linear(c["joint_embedding_dim"], d)
        self.rise = Linear(1, d)
        self.virtual_joint = nn.Parameter(torch.randn(d) * 0.02)
        self.temporal = nn.ModuleList()
        self.spatial = nn.ModuleList()
        for _ in range(c["blocks"]):
            self.temporal.append(DownBlock(d))
            for _ in range(c["attention_layers"]):
                self.spatial.append(SpatialAttention(d, c["heads"]))
        self.attention_layers = c["attention_layers"]
        self.final_norm = nn.LayerNorm(d)
        self.to_latent = Linear(d, c["code_dim"])

    def forward(self, features, joint_mask, joint_embeddings):
        """Model space (B, T, J, MODEL_CHANNELS) -> latent (B, T / r, C)."""
        b, t = features.shape[:2]
        joints = self.input(features) + self.embedding(joint_embeddings).unsqueeze(1)
        # The virtual joint starts as the learnt vector plus the root joint's input and its rise per frame.
        virtual_joint = self.virtual_joint.view(1, 1, 1, -1) + joints[:, :, :1] + self.rise(root_rise(features))
        tokens = torch.cat([virtual_joint, joints], 2)
        bias = key_bias(joint_mask)
        blocks = len(self.temporal)
        for block in range(blocks):
            tokens = per_token(self.temporal[block], tokens)
            for layer in range(self.attention_layers):
                last = block + 1 == blocks and layer + 1 == self.attention_layers
                tokens = self.spatial[block * self.attention_layers + layer](tokens, bias, last)
        return self.to_latent(self.final_norm(tokens.select(2, 0)))


class NecDecoder(nn.Module):
    def __init__(self, c):
        super().__init__()
        d, code_dim = c["dim"], c["code_dim"]
        self.virtual_from_latent = Linear(code_dim, d)
        self.joint_from_latent = Linear(code_dim, d)
        self.joint_from_embedding = Linear(c["joint_embedding_dim"], d, bias=False)
        self.joint_hidden = Linear(d, d)
        self.spatial = nn.ModuleList()
        self.temporal = nn.ModuleList()
        for _ in range(c["blocks"]):
            for _ in range(c["attention_layers"]):
                self.spatial.append(SpatialAttention(d, c["heads"]))
            self.temporal.append(UpBlock(d))
        self.attention_layers = c["attention_layers"]
        self.output = Linear(d, MODEL_CHANNELS)
        self.path = Linear(d, 4)

    def forward(self, quantized, joint_mask, joint_embeddings):
        """(B, S, C) -> model space (B, S r, J, MODEL_CHANNELS), zero at padded joints."""
        joints = joint_mask.size(1)
        virtual_joint = self.virtual_from_latent(quantized).unsqueeze(2)
        joint_features = self.joint_hidden(torch.relu(
            self.joint_from_latent(quantized).unsqueeze(2) + self.joint_from_embedding(joint_embeddings).unsqueeze(1)))
        tokens = torch.cat([virtual_joint, joint_features], 2)
        bias = decoder_attention_bias(joint_mask)
        for block in range(len(self.temporal)):
            for layer in range(self.attention_layers):
                tokens = self.spatial[block * self.attention_layers + layer](tokens, bias)
            tokens = per_token(self.temporal[block], tokens)
        out = self.output(tokens.narrow(2, 1, joints)) + rest_pose_features()
        # The root's path (Δx', Δz', yaw rate, rise) from the virtual joint; R̃ and the height's level stay the
        # root joint's: height = the level averaged over the window + the summed rise, centred.
        path = self.path(tokens.select(2, 0))
        root = out.select(2, 0)
        shape = F.pad((path[:, 1:, 3:4] / ROOT_MOTION_SCALE).cumsum(1), (0, 0, 1, 0))
        height = root[..., 1:2].mean(1, keepdim=True) + shape - shape.mean(1, keepdim=True)
        root = torch.cat([path.narrow(-1, 0, 1), height, path.narrow(-1, 1, 1), root.narrow(-1, 3, 6),
                          path.narrow(-1, 2, 1)], -1)
        joined = torch.cat([root.unsqueeze(2), out.narrow(2, 1, joints - 1)], 2)
        return joined * joint_mask.view(joint_mask.size(0), 1, joints, 1).to(joined.dtype)


# ---- Residual quantizer (quantizer.cpp) ----

def sample_rows(rows, weight, error, count):
    """count rows drawn with replacement, row i with a chance proportional to weight_i |error_i|^2 (k-means++)."""
    squared = torch.nan_to_num(weight * error.pow(2).sum(1), 0.0, 0.0, 0.0)
    chance = squared + weight * (1e-6 * squared.max()).clamp_min(1e-12)
    return rows.index_select(0, torch.multinomial(chance, count, replacement=True))


class ResidualQuantizer(nn.Module):
    def __init__(self, c):
        super().__init__()
        self.c = c
        r, k, d = c["layers"], c["codebook_size"], c["code_dim"]
        self.register_buffer("codebooks", torch.randn(r, k, d))
        self.register_buffer("ema_counts", torch.ones(r, k))
        self.register_buffer("ema_sums", self.codebooks.clone())
        self.register_buffer("initialized", torch.zeros((), dtype=torch.bool))
        self.pending = None  # (counts (R, K), sums (R, K, C), rows per layer) since the last update_codebooks()

    @torch.no_grad()
    def update_codebooks(self):
        """quantizer.cpp update_codebooks: the EMA step from the collected statistics, then dead-code restarts."""
        if self.pending is None:
            return
        c = self.c
        size, dim, decay, threshold = c["codebook_size"], c["code_dim"], c["ema_decay"], c["dead_code_threshold"]
        counts, sums, rows = self.pending
        for r in range(c["layers"]):
            if not bool((counts[r].sum() > 0).item()):
                continue
            codebook = self.codebooks[r]
            self.ema_counts[r].mul_(decay).add_(counts[r], alpha=1.0 - decay)
            self.ema_sums[r].mul_(decay).add_(sums[r], alpha=1.0 - decay)
            total_count = self.ema_counts[r].sum()
            smoothed = (self.ema_counts[r] + LAPLACE_EPSILON) / (total_count + size * LAPLACE_EPSILON) * total_count
            codebook.copy_(self.ema_sums[r] / smoothed.unsqueeze(1))
            if threshold <= 0:
                continue
            dead = (self.ema_counts[r] < threshold).unsqueeze(1)
            if not bool(dead.any().item()):
                continue
            kept = torch.cat(rows[r]) if rows[r] else torch.zeros(0, 2 * dim + 1)
            fresh = sample_rows(kept[:, :dim], kept[:, 2 * dim], kept[:, dim:2 * dim], size)
            codebook.copy_(torch.where(dead, fresh, codebook))
            self.ema_sums[r].copy_(torch.where(dead, fresh * threshold, self.ema_sums[r]))
            self.ema_counts[r].masked_fill_(dead.squeeze(1), threshold)
        self.pending = None

    def forward(self, latent, mask):
        """latent (N, C), mask (N) bool -> quantized (N, C), codes (N, R), commitment, perplexity (R)."""
        c = self.c
        layers, size = c["layers"], c["codebook_size"]
        rows = latent.size(0)
        weight = mask.to(self.codebooks.dtype)
        used_layers, update, seed = layers, False, False
        if self.training:
            if c["quantize_dropout"] > 0 and layers > 1 and \
                    torch.rand(1, dtype=torch.float64).item() < c["quantize_dropout"]:
                used_layers = torch.randint(1, layers + 1, (1,), dtype=torch.long).item()
            if rows > 0:
                flags = torch.stack([weight.sum() > 0, self.initialized]).cpu()
                update = bool(flags[0].item())
                seed = update and not bool(flags[1].item())

        codes = torch.full((rows, layers), -1, dtype=torch.long)
        perplexity = torch.zeros(layers)
        with torch.no_grad():
            residual = latent.detach().to(self.codebooks.dtype).clone()
            total = torch.zeros_like(residual)
            kept = weight.sum().clamp_min(1.0)
            for r in range(used_layers):
                codebook = self.codebooks[r]
                if seed:
                    codebook.copy_(sample_rows(residual, weight, residual, size))
                    self.ema_sums[r].copy_(codebook)
                    self.ema_counts[r].fill_(1.0)
                distance = torch.addmm((codebook * codebook).sum(1).unsqueeze(0), residual, codebook.t(),
                                       beta=1, alpha=-2)
                index = distance.argmin(1)
                chosen = codebook.index_select(0, index)
                codes.select(1, r).copy_(index)
                counts = torch.zeros(size).index_add_(0, index, weight)
                usage = counts / kept
                perplexity.select(0, r).copy_(torch.exp(-(usage * torch.log(usage.clamp_min(1e-10))).sum()))
                if update:
                    # Kept for update_codebooks(): the EMA moves once per optimizer step (quantizer.cpp).
                    sums = torch.zeros(size, c["code_dim"]).index_add_(0, index, residual * weight.unsqueeze(1))
                    if self.pending is None:
                        self.pending = (torch.zeros_like(self.ema_counts), torch.zeros_like(self.ema_sums),
                                        [[] for _ in range(layers)])
                    self.pending[0][r].add_(counts)
                    self.pending[1][r].add_(sums)
                    if c["dead_code_threshold"] > 0:
                        self.pending[2][r].append(torch.cat([residual, residual - chosen, weight.unsqueeze(1)], 1))
                total += chosen
                residual -= chosen
            if seed:
                self.initialized.fill_(True)
            quantized = total.to(latent.dtype)
        squared_error = (latent - quantized).pow(2).mean(1)
        commitment = c["commitment_weight"] * (squared_error * weight.to(latent.dtype)).sum() / \
            weight.sum().clamp_min(1.0).to(latent.dtype)
        return latent + (quantized - latent).detach(), codes, commitment, perplexity


# ---- Model space (model_space.cpp) ----

def yaw_matrix(angle):
    c, s = torch.cos(angle), torch.sin(angle)
    zero, one = torch.zeros_like(angle), torch.ones_like(angle)
    return torch.stack([c, zero, s, zero, one, zero, -s, zero, c], -1).view(*angle.shape, 3, 3)


def turned_displacement(root, turn, scale):
    delta = torch.matmul(root.narrow(-1, 0, 3), turn.transpose(-1, -2))
    return delta * torch.tensor([scale, 1.0, scale], dtype=root.dtype)


def with_heights(root):
    """Root rows with Θ's Δy (frame 0: the height) in channel 1 -> the height of every frame there."""
    return torch.cat([root[..., :1], root[..., 1:2].cumsum(1), root[..., 2:]], -1)


def with_height_steps(root):
    """The inverse of with_heights."""
    height = root[..., 1:2]
    return torch.cat([root[..., :1], torch.cat([height[:, :1], height[:, 1:] - height[:, :-1]], 1), root[..., 2:]], -1)


def features_to_model_space(features):
    """(B, T, J, 9) -> (B, T, J, MODEL_CHANNELS): body-frame Δ, root height, root orientation without its heading,
    yaw rate."""
    root = features.select(2, 0)
    rotation = rot6d_to_matrix(root.narrow(-1, 3, 6))
    heading = heading_matrix(rotation)
    untwisted = torch.matmul(heading.transpose(-1, -2), rotation)
    step = torch.matmul(heading[:, :-1].transpose(-1, -2), heading[:, 1:])
    rate = nn.functional.pad(torch.atan2(step[..., 0, 2], step[..., 0, 0]), (1, 0))  # frame 0 does not turn
    model_root = torch.cat([with_heights(turned_displacement(root, heading.select(1, 0), ROOT_MOTION_SCALE)),
                            matrix_to_rot6d(untwisted), (rate * YAW_RATE_SCALE).unsqueeze(-1)], -1)
    others = nn.functional.pad(features.narrow(2, 1, features.size(2) - 1), (0, 1))
    return torch.cat([model_root.unsqueeze(2), others], 2)


def model_space_to_features(model, start_heading):
    """The inverse, with the root's heading at frame 0 (B): (B, T, J, MODEL_CHANNELS) -> Θ (B, T, J, 9)."""
    root = model.select(2, 0)
    untwisted = rot6d_to_matrix(root.narrow(-1, 3, 6))
    rate = nn.functional.pad(root[:, 1:, 9] / YAW_RATE_SCALE, (1, 0))
    start = start_heading.to(model.dtype).view(-1, 1)
    rotation = torch.matmul(yaw_matrix(start + rate.cumsum(1)), untwisted)
    feature_root = torch.cat([turned_displacement(with_height_steps(root), yaw_matrix(start[:, 0]).transpose(-1, -2),
                                                  1.0 / ROOT_MOTION_SCALE), matrix_to_rot6d(rotation)], -1)
    return torch.cat([feature_root.unsqueeze(2), model.narrow(2, 1, model.size(2) - 1).narrow(-1, 0, 9)], 2)


def start_heading(features):
    """model_space.cpp start_heading: the root's heading at frame 0, (B) radians."""
    heading = heading_matrix(rot6d_to_matrix(features[:, 0, 0, 3:9]))
    return torch.atan2(heading[..., 0, 2], heading[..., 0, 0])


def distinct_joint_embeddings(embeddings, joint_mask):
    """tokenizer.cpp distinct_joint_embeddings: centred over the skeleton's real joints, unit RMS."""
    real = joint_mask.to(embeddings.dtype).unsqueeze(-1)
    count = real.sum(1, keepdim=True).clamp_min(1.0)
    centred = (embeddings - (embeddings * real).sum(1, keepdim=True) / count) * real
    mean_square = centred.pow(2).sum((1, 2), keepdim=True) / (count * float(embeddings.size(2)))
    return centred * mean_square.clamp_min(1e-12).rsqrt()


class Tokenizer(nn.Module):
    def __init__(self, c):
        super().__init__()
        self.downsampling = 2 ** c["blocks"]
        self.encoder = NecEncoder(c)
        self.decoder = NecDecoder(c)
        self.quantizer = ResidualQuantizer(c)

    def forward(self, features, joint_mask, frame_mask, joint_embeddings):
        joint_mask = joint_mask.to(torch.bool)
        joint_embeddings = distinct_joint_embeddings(joint_embeddings, joint_mask)
        latent = self.encoder(features_to_model_space(features), joint_mask, joint_embeddings)  # (B, S, C)
        b, s, code_dim = latent.shape
        step_mask = frame_mask.to(torch.bool).reshape(b, s, self.downsampling).any(-1)
        quantized, codes, commitment, perplexity = self.quantizer(latent.reshape(b * s, code_dim),
                                                                  step_mask.reshape(b * s))
        reconstruction = model_space_to_features(self.decoder(quantized.view(b, s, code_dim), joint_mask,
                                                              joint_embeddings), start_heading(features))
        return reconstruction, codes.view(b, s, -1), commitment, perplexity


# ---- Differentiable FK (fk.cpp) ----

def normalized(v):
    return v * (v * v).sum(-1, keepdim=True).clamp_min(TINY_SQUARED_NORM).rsqrt()


def rot6d_to_matrix(rot6d):
    a, b = rot6d.narrow(-1, 0, 3), rot6d.narrow(-1, 3, 3)
    x = normalized(a)
    y = normalized(b - (x * b).sum(-1, keepdim=True) * x)
    z = torch.linalg.cross(x, y, dim=-1)
    return torch.stack([x, y, z], -1)


def matrix_to_rot6d(matrix):
    return torch.cat([matrix.select(-1, 0), matrix.select(-1, 1)], -1)


def heading_matrix(rotation):
    c = rotation.select(-1, 0).select(-1, 0) + rotation.select(-1, 2).select(-1, 2)
    s = rotation.select(-2, 0).select(-1, 2) - rotation.select(-2, 2).select(-1, 0)
    squared = c * c + s * s
    defined = squared > TINY_SQUARED_NORM
    inverse = squared.clamp_min(TINY_SQUARED_NORM).rsqrt()
    cosine = torch.where(defined, c * inverse, torch.ones_like(c))
    sine = torch.where(defined, s * inverse, torch.zeros_like(s))
    zero, one = torch.zeros_like(c), torch.ones_like(c)
    rows = torch.stack([cosine, zero, sine, zero, one, zero, -sine, zero, cosine], -1)
    return rows.view(rotation.shape)


def features_to_positions(features, parents, offsets):
    """(B, T, J, 9), parents (B, J), offsets (B, J, 3) -> positions (B, T, J, 3)."""
    batch, frames, joints = features.shape[:3]
    local = rot6d_to_matrix(features.narrow(-1, 3, 6))
    root_rotation = local.select(2, 0)
    delta = features.select(2, 0).narrow(-1, 0, 3)
    world_delta = torch.matmul(heading_matrix(root_rotation), delta.unsqueeze(-1)).squeeze(-1)
    root_position = world_delta.cumsum(1)
    rest_offsets = offsets.to(features.dtype).narrow(1, 1, joints - 1)
    rotation = torch.cat([local, torch.eye(3).expand(batch, frames, 1, 3, 3)], 2)
    translation = torch.cat([root_position.unsqueeze(2),
                             rest_offsets.unsqueeze(1).expand(batch, frames, joints - 1, 3),
                             torch.zeros(batch, frames, 1, 3)], 2)
    ancestor = parents.to(torch.long).clone()
    ancestor.select(1, 0).fill_(joints)
    ancestor = torch.where(ancestor < 0, torch.zeros_like(ancestor), ancestor)
    ancestor = torch.cat([ancestor, torch.full((batch, 1), joints, dtype=torch.long)], 1)
    reach = 1
    while reach < joints:
        index = ancestor.view(batch, 1, joints + 1, 1)
        above_rotation = torch.gather(rotation, 2, index.unsqueeze(-1).expand(batch, frames, joints + 1, 3, 3))
        above_translation = torch.gather(translation, 2, index.expand(batch, frames, joints + 1, 3))
        translation = above_translation + torch.matmul(above_rotation, translation.unsqueeze(-1)).squeeze(-1)
        rotation = torch.matmul(above_rotation, rotation)
        ancestor = torch.gather(ancestor, 1, ancestor)
        reach *= 2
    return translation.narrow(2, 0, joints).contiguous()


# ---- Loss (loss.cpp) ----

def masked_mean(error, weight):
    count = weight.sum() * float(error.size(-1))
    return (error * weight.unsqueeze(-1)).sum() / count.clamp_min(1.0)


def masked_l1(a, b, weight):
    return masked_mean((a - b).abs(), weight)


def loss_weights_at(w, step):
    """LossWeights::at_step: the positions' and velocities' terms count from positions_from_step on."""
    if step >= w["positions_from_step"]:
        return w
    return dict(w, position=0.0, velocity=0.0)


def reconstruction_loss(prediction, x, commitment, w):
    b, t, j = prediction.shape[:3]
    frame = x["frame_mask"].to(prediction.dtype)
    real = frame.view(b, t, 1) * x["joint_mask"].to(prediction.dtype).view(b, 1, j)
    target = x["features"]
    rotation = masked_mean((prediction.narrow(-1, 3, 6) - target.narrow(-1, 3, 6)).square(), real)
    root_motion = [features_to_model_space(f[:, :, :1]).select(2, 0)[..., [0, 1, 2, 9]] for f in (prediction, target)]
    root = masked_l1(root_motion[0], root_motion[1], frame)
    predicted = features_to_positions(prediction, x["parents"], x["offsets"])
    with torch.no_grad():
        expected = features_to_positions(target, x["parents"], x["offsets"])
    position = masked_l1(predicted, expected, real)
    both = real[:, 1:] * real[:, :-1]
    velocity = masked_l1(predicted[:, 1:] - predicted[:, :-1], expected[:, 1:] - expected[:, :-1], both)
    rise = [f[:, 1:, 0, 1:2] * ROOT_MOTION_SCALE for f in (prediction, target)]
    vertical = masked_l1(rise[0], rise[1], frame[:, 1:] * frame[:, :-1])
    commitment = commitment.to(prediction.dtype).reshape(())
    total = w["rotation"] * rotation + w["root"] * root + w["position"] * position + \
        w["velocity"] * velocity + w["vertical"] * vertical + commitment
    terms = torch.stack([rotation, root, position, velocity, vertical, commitment]).detach().to("cpu", torch.float64)
    return total, terms.tolist()


# ---- Synthetic batch (bench_tat.cpp synthetic_batch, same draws in the same order) ----

def random_features(batch, frames, joints):
    rotations = matrix_to_rot6d(rot6d_to_matrix(torch.randn(batch, frames, joints, 6)))
    root_delta = torch.randn(batch, frames, 3) * 0.02
    root_delta.select(1, 0).zero_()
    root_delta.select(1, 0).select(1, 1).fill_(0.9)
    translation = torch.zeros(batch, frames, joints, 3)
    translation.select(2, 0).copy_(root_delta)
    return torch.cat([translation, rotations], -1)


def synthetic_batch(batch, frames, joints, embedding_dim):
    x = {"features": random_features(batch, frames, joints)}
    index = torch.arange(joints, dtype=torch.long)
    x["parents"] = torch.minimum((torch.rand(batch, joints) * index.to(torch.float)).floor().to(torch.long), index - 1)
    x["offsets"] = torch.randn(batch, joints, 3) * 0.1
    x["offsets"].select(1, 0).zero_()
    x["joint_mask"] = torch.ones(batch, joints, dtype=torch.bool)
    x["frame_mask"] = torch.ones(batch, frames, dtype=torch.bool)
    x["embeddings"] = torch.randn(batch, joints, embedding_dim)
    return x


# ---- The step and its measurement ----

class Trainee(ScheduledTrainee):
    def __init__(self, c, joints):
        torch.manual_seed(SEED)
        self.x = synthetic_batch(c["batch_size"], c["window_frames"], joints, c["joint_embedding_dim"])
        model = Tokenizer(c)
        super().__init__(c, model, model.parameters())

    def step(self):
        """TatTrainer::step without the batch conversion and the OwO embeddings."""
        lr = self.next_rate()
        self.model.train()
        x = self.x
        reconstruction, _, commitment, perplexity = self.model(x["features"], x["joint_mask"], x["frame_mask"],
                                                               x["embeddings"])
        total, _ = reconstruction_loss(reconstruction, x, commitment, loss_weights_at(self.c["loss"], self.steps))
        self.optimizer.zero_grad()
        total.backward()
        self.optimizer_step(lr)
        self.model.quantizer.update_codebooks()
        perplexity.to("cpu", torch.float64).tolist()
        return total.item()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_arguments(parser, "tat_cpu.json and owo_cpu.json", default_repetitions=5)
    parser.add_argument("--joints", type=int, nargs="+", default=[22, 100], help="skeleton sizes (default: 22 100)")
    parser.add_argument("--iterations", type=int, nargs="+", default=[3, 1],
                        help="timed steps per repetition, one per --joints value (default: 3 1, as bench_tat)")
    args = parser.parse_args()
    if len(args.iterations) != len(args.joints):
        parser.error("give one --iterations value per --joints value")
    keep_large_allocations_in_heap()
    c = read_config(args.configs)
    settings = [({"joints": joints}, iterations) for joints, iterations in zip(args.joints, args.iterations)]
    print_json(run_settings("tat", settings, lambda setting: Trainee(c, setting["joints"]), args))


if __name__ == "__main__":
    main()

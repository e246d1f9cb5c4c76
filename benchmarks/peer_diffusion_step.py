#!/usr/bin/env python3
"""The diffusion model's training step in PyTorch (Python): the peer of bench_diffusion's BM_DiffusionTrainStep.

A line-by-line re-implementation of the NEC motion diffusion model of
diffusion/src/denoiser.cpp, noise_schedule.cpp, objective.cpp and training.cpp
(with the use-lite text encoder of text/encoder/src/text_encoder.cpp and the
attention of layers/src/transformer.cpp, both in peer_layers.py): the same
modules created in the same order (so the same torch.manual_seed gives the
same initial weights), the same forward, the same loss, and the step of
diffusion/synthetic.h (zero_grad, backward, the gradient clip, AdamW at the
scheduled learning rate, over the parameters the stage trains) on its
synthetic batch, drawn with the same torch random calls. Its first two losses
therefore equal bench_diffusion's counters loss_step0 / loss_step1 up to float
rounding.

    /usr/bin/python3 benchmarks/peer_diffusion_step.py --expect-parameters N [--stage motion pose]
        [--joints 22 100] [--iterations I...] [--threads 1 2] [--repetitions 3]
        [--configs DIR]   # diffusion_pose_cpu.json, diffusion_motion_cpu.json and owo_cpu.json, as bench_diffusion
        [--profile-ops DIR]   # one more step per setting under the op profiler, as bench_diffusion --profile_ops=DIR

Prints one JSON object on stdout (per stage and J: wall-clock and process CPU
time per step in ms over the repetitions, the first losses, parameter count,
peak memory of a step); exits 1 when the parameter count differs from
--expect-parameters (the count bench_diffusion reports). Runs with nec's
allocator policy and shares its measurement with the other peers
(peer_step.py).
"""
import argparse
import json
import math
import os
import sys

import torch
import torch.nn as nn
import torch.nn.functional as F

from peer_layers import Linear, TextEncoder, multi_head_attention, padding_bias, USE_LITE_WIDTH
from peer_step import add_arguments, keep_large_allocations_in_heap, print_json, run_settings, ScheduledTrainee
# The tokenizer's peer holds model space, Θ's random draws and the schedule already.
from peer_tat_step import features_to_model_space, random_features, MODEL_CHANNELS

SEED = 0                  # torch.manual_seed before inputs and model, as bench_diffusion
NORM_EPSILON = 1e-6       # denoiser.cpp kNormEpsilon
MIN_STD = 1e-3            # denoiser.cpp kMinStd
ROTATION_BEGIN, ROTATION_CHANNELS = 3, 6
SCHEDULE_OFFSET = 0.008   # noise_schedule.cpp kOffset
MAX_BETA = 0.999          # noise_schedule.cpp kMaxBeta
POSE_STAND_IN_STD = 0.05  # synthetic.h kPoseStandInStd
SYNTHETIC_PIECES = 12     # synthetic.h kSyntheticPieces


# ---- Configuration (defaults of diffusion/training.h, denoiser.h, text_encoder.h) ----

def read_config(configs, stage):
    def load(name):
        with open(os.path.join(configs, name)) as f:
            return json.load(f)

    pose = load("diffusion_pose_cpu.json")
    raw = pose if stage == "pose" else load("diffusion_motion_cpu.json")
    model = pose.get("model", {})  # the motion stage takes the pose model's
    text = model.get("text", {})
    optimizer = raw.get("optimizer", {})
    if text.get("backbone", "pieces") != "use-lite" or text.get("layers", 2) < 1 or text.get("piece_memory", False):
        sys.exit("peer_diffusion_step: only the use-lite text backbone with layers >= 1 is re-implemented")
    if model.get("joint_identity", "owo") != "owo":
        sys.exit("peer_diffusion_step: only joint_identity \"owo\" is re-implemented")
    return {
        "dim": model.get("dim", 128),
        "heads": model.get("heads", 4),
        "layers": model.get("layers", 4),
        "feedforward": model.get("feedforward", 512),
        "noise_steps": model.get("noise_steps", 1000),
        "skeleton_dim": load("owo_cpu.json")["encoder"]["dim"],
        "text": {k: text.get(k, d) for k, d in (("dim", 128), ("layers", 2), ("heads", 4), ("feedforward", 256),
                                                ("max_pieces", 48), ("output_dim", 128), ("dropout", 0.1),
                                                ("piece_dropout", 0.1))},
        "learning_rate": optimizer.get("learning_rate", 2e-4),
        "final_lr_fraction": optimizer.get("final_lr_fraction", 0.1),
        "warmup_steps": optimizer.get("warmup_steps", 100),
        "weight_decay": optimizer.get("weight_decay", 0.0),
        "grad_clip": optimizer.get("grad_clip", 1.0),
        "steps": raw.get("steps", 3000),
        "batch_size": raw.get("batch_size", 32),
        "window_frames": raw.get("data", {}).get("window_frames", 64),
        "pose_frames": raw.get("pose_frames", 8),
        "caption_dropout": raw.get("caption_dropout", 0.1),
        "velocity_weight": raw.get("velocity_weight", 0.0),
    }


# ---- The denoiser (denoiser.cpp) ----

def encoding_mlp(width_in, dim):
    """Linear-SiLU-Linear. The C++ builds both Linears as arguments of one call, which GCC evaluates right to left:
    the second layer's weights are drawn first."""
    second = Linear(dim, dim)
    first = Linear(width_in, dim)
    return nn.Sequential(first, nn.SiLU(), second)


def layer_norm(x):
    return F.layer_norm(x, (x.size(-1),), eps=NORM_EPSILON)


def modulate(x, shift, scale):
    """x (B, G, L, D), shift and scale (B, D)."""
    return x * (1 + scale.view(scale.size(0), 1, 1, -1)) + shift.view(shift.size(0), 1, 1, -1)


def group_bias(mask, groups):
    """(B, N) bool repeated for each of `groups` groups -> (B * groups, 1, 1, N)."""
    bias = padding_bias(mask)
    return bias.unsqueeze(1).expand(mask.size(0), groups, 1, 1, mask.size(1)).reshape(-1, 1, 1, mask.size(1))


def sinusoidal_encoding(positions, dim):
    half = dim // 2
    frequencies = torch.exp(torch.arange(half, dtype=torch.float32) * (-math.log(10000.0) / max(1, half)))
    angles = positions.to(torch.float32).unsqueeze(-1) * frequencies
    out = torch.cat([torch.sin(angles), torch.cos(angles)], -1)
    return F.pad(out, (0, dim - out.size(-1))) if out.size(-1) < dim else out


def channel_mask(joint_mask):
    """(B, J) bool -> (B, J, MODEL_CHANNELS): the root uses every channel, the other joints their rot6D."""
    used = torch.zeros(joint_mask.size(1), MODEL_CHANNELS, dtype=torch.bool)
    used[:, ROTATION_BEGIN:ROTATION_BEGIN + ROTATION_CHANNELS] = True
    used[0] = True
    return used.unsqueeze(0) & joint_mask.unsqueeze(-1)


class DitBlock(nn.Module):
    def __init__(self, dim, heads, feedforward):
        super().__init__()
        self.heads = heads
        self.modulation = Linear(dim, 6 * dim)
        self.qkv = Linear(dim, 3 * dim)
        self.out = Linear(dim, dim)
        self.mlp_in = Linear(dim, feedforward)
        self.mlp_out = Linear(feedforward, dim)
        with torch.no_grad():
            self.modulation.weight.zero_()
            self.modulation.bias.zero_()

    def forward(self, x, c, bias, positions):
        b, g, l, d = x.shape
        m = self.modulation(F.silu(c)).chunk(6, 1)
        h = modulate(layer_norm(x), m[0], m[1])
        if positions is not None:
            h = h + positions
        attended = self.out(multi_head_attention(self.qkv(h.reshape(b * g, l, d)), self.heads, bias))
        y = x + m[2].view(b, 1, 1, d) * attended.view(b, g, l, d)
        mlp = self.mlp_out(F.gelu(self.mlp_in(modulate(layer_norm(y), m[3], m[4]))))
        return y + m[5].view(b, 1, 1, d) * mlp


class MotionDenoiser(nn.Module):
    def __init__(self, c):
        super().__init__()
        d = c["dim"]
        self.dim = d
        self.text = TextEncoder(c["text"])
        self.caption_in = encoding_mlp(c["text"]["output_dim"], d)
        self.null_caption = nn.Parameter(torch.randn(d) * 0.02)
        self.time_in = encoding_mlp(d, d)
        self.motion_in = Linear(MODEL_CHANNELS, d)
        self.owo_in = encoding_mlp(c["skeleton_dim"], d)
        self.spatial = nn.ModuleList()
        self.temporal = nn.ModuleList()
        for _ in range(c["layers"]):
            self.spatial.append(DitBlock(d, c["heads"], c["feedforward"]))
            self.temporal.append(DitBlock(d, c["heads"], c["feedforward"]))
        self.frame_in = encoding_mlp(d, d)
        self.final_modulation = Linear(d, 2 * d)
        self.out = Linear(d, MODEL_CHANNELS)
        with torch.no_grad():
            for zero in (self.final_modulation, self.out):
                zero.weight.zero_()
                zero.bias.zero_()
        self.register_buffer("data_mean", torch.zeros(2, MODEL_CHANNELS))
        self.register_buffer("data_std", torch.ones(2, MODEL_CHANNELS))

    def caption_condition(self, text, drop_text):
        caption = self.caption_in(self.text(text)[0])
        return torch.where(drop_text.unsqueeze(-1), self.null_caption.expand_as(caption), caption)

    def forward(self, x_t, t, caption, joint_embeddings, joint_mask, frame_mask, temporal):
        frames, joints = x_t.size(1), x_t.size(2)
        c = self.time_in(sinusoidal_encoding(t, self.dim)) + caption
        identity = self.owo_in(joint_embeddings) * joint_mask.unsqueeze(-1).to(torch.float32)
        h = self.motion_in(x_t) + identity.unsqueeze(1)
        spatial_bias = group_bias(joint_mask, frames)
        if temporal:
            temporal_bias = group_bias(frame_mask, joints)
            positions = self.frame_in(sinusoidal_encoding(torch.arange(frames, dtype=torch.int64), self.dim))
        for i in range(len(self.spatial)):
            h = self.spatial[i](h, c, spatial_bias, None)
            if temporal:
                h = self.temporal[i](h.transpose(1, 2), c, temporal_bias, positions).transpose(1, 2)
        m = self.final_modulation(F.silu(c)).chunk(2, 1)
        return self.out(modulate(layer_norm(h), m[0], m[1]))

    def per_joint(self, statistic, joints):
        return torch.cat([statistic.narrow(0, 0, 1), statistic.narrow(0, 1, 1).expand(joints - 1, -1)])

    def standardize(self, model_space):
        j = model_space.size(-2)
        return (model_space - self.per_joint(self.data_mean, j)) / self.per_joint(self.data_std, j)

    @torch.no_grad()
    def fit_statistics(self, clips):
        roots, others = [], []
        for clip in clips:
            x = clip.to(torch.float64)
            roots.append(x.select(1, 0))
            if x.size(1) > 1:
                others.append(x.narrow(1, 1, x.size(1) - 1).narrow(2, ROTATION_BEGIN, ROTATION_CHANNELS)
                              .reshape(-1, ROTATION_CHANNELS))
        mean = torch.zeros(2, MODEL_CHANNELS, dtype=torch.float64)
        std = torch.ones(2, MODEL_CHANNELS, dtype=torch.float64)
        root = torch.cat(roots)
        mean[0] = root.mean(0)
        std[0] = root.std(0, unbiased=False)
        # The horizontal displacement: mean 0 and one std for x and z (turning it commutes with standardizing).
        horizontal = torch.sqrt((root.select(1, 0).square().mean() + root.select(1, 2).square().mean()) / 2)
        for k in (0, 2):
            mean[0][k] = 0.0
            std[0][k] = horizontal
        if others:
            rows = torch.cat(others)
            mean[1].narrow(0, ROTATION_BEGIN, ROTATION_CHANNELS).copy_(rows.mean(0))
            std[1].narrow(0, ROTATION_BEGIN, ROTATION_CHANNELS).copy_(rows.std(0, unbiased=False))
        self.data_mean.copy_(mean.to(torch.float32))
        self.data_std.copy_(std.clamp_min(MIN_STD).to(torch.float32))

    def is_pose_parameter(self, name):
        return not name.startswith("temporal.") and not name.startswith("frame_in.")

    def trained_parameters(self, stage):
        """objective.cpp trained_parameters: the pose model's, or the temporal blocks' then the frame encoding's."""
        if stage == "pose":
            return [p for name, p in self.named_parameters() if self.is_pose_parameter(name)]
        return list(self.temporal.parameters()) + list(self.frame_in.parameters())


# ---- Noise schedule and loss (noise_schedule.cpp, training.cpp, objective.cpp) ----

def alpha_bars(steps):
    def f(u):
        angle = (u / steps + SCHEDULE_OFFSET) / (1.0 + SCHEDULE_OFFSET) * math.pi / 2.0
        return math.cos(angle) * math.cos(angle)

    out, alpha_bar = [], 1.0
    for t in range(steps):
        beta = min(MAX_BETA, 1.0 - f(float(t + 1)) / f(float(t)))
        alpha_bar *= 1.0 - beta
        out.append(alpha_bar)
    return out


def add_noise(alpha_bar, x0, noise, t):
    a = torch.tensor(alpha_bar, dtype=torch.float64).index_select(0, t).to(x0.dtype)
    a = a.view(x0.size(0), *([1] * (x0.dim() - 1)))
    return a.sqrt() * x0 + (1.0 - a).sqrt() * noise


def denoising_loss(predicted, target, used, global_items):
    weight = used.to(predicted.dtype)
    per_item = ((predicted - target).square() * weight).sum((1, 2, 3)) / weight.sum((1, 2, 3)).clamp_min(1.0)
    return per_item.sum() / float(global_items)


def velocity_loss(predicted, target, used, global_items):
    frames = predicted.size(1)

    def velocity(x):
        return x.narrow(1, 1, frames - 1) - x.narrow(1, 0, frames - 1)

    return denoising_loss(velocity(predicted), velocity(target),
                          used.narrow(1, 1, frames - 1) & used.narrow(1, 0, frames - 1), global_items)


def denoising_objective(model, alpha_bar, x, stage, velocity_weight):
    b = x["motion"].size(0)
    used = channel_mask(x["joint_mask"]).unsqueeze(1) & x["frame_mask"].view(b, -1, 1, 1)
    x0 = torch.where(used, model.standardize(x["motion"]), torch.zeros_like(x["motion"]))
    x_t = add_noise(alpha_bar, x0, x["noise"] * used, x["t"])
    condition = model.caption_condition(x["text"], x["drop_text"])
    temporal = stage == "motion"
    predicted = model(x_t, x["t"], condition, x["joint_embeddings"], x["joint_mask"], x["frame_mask"], temporal)
    loss = denoising_loss(predicted, x0, used, x["global_items"])
    if temporal and velocity_weight > 0:
        loss = loss + velocity_weight * velocity_loss(predicted, x0, used, x["global_items"])
    return loss


# ---- Synthetic batch (diffusion/src/synthetic.cpp, same draws in the same order) ----

def first_positions(counts, width):
    return torch.arange(width, dtype=torch.long).unsqueeze(0) < counts.unsqueeze(1)


def synthetic_batch(c, stage, joints):
    b, frames = c["batch_size"], c["window_frames"]
    features = random_features(b, frames, joints)
    index = torch.arange(joints, dtype=torch.long)
    parents = torch.minimum((torch.rand(b, joints) * index.to(torch.float)).floor().to(torch.long), index - 1)
    offsets = torch.randn(b, joints, 3) * 0.1
    offsets.select(1, 0).zero_()
    joint_counts = joints - (torch.rand(b) * float(joints // 4 + 1)).floor().to(torch.long)
    frame_counts = frames - (torch.rand(b) * float(frames // 2 + 1)).floor().to(torch.long)
    joint_counts[0] = joints
    frame_counts[0] = frames
    joint_mask, frame_mask = first_positions(joint_counts, joints), first_positions(frame_counts, frames)
    real = (frame_mask.view(b, frames, 1, 1) & joint_mask.view(b, 1, joints, 1)).to(torch.float)
    features = features * real
    embeddings = torch.randn(b, joints, c["skeleton_dim"]) * joint_mask.unsqueeze(-1).to(torch.float)

    piece_counts = 1 + (torch.rand(b) * float(SYNTHETIC_PIECES)).floor().to(torch.long)
    mask = first_positions(piece_counts, int(piece_counts.max().item()))
    encoder_features = torch.randn(b, mask.size(1), USE_LITE_WIDTH) * (1.0 / math.sqrt(float(USE_LITE_WIDTH))) * \
        mask.unsqueeze(-1).to(torch.float)
    sentence = torch.randn(b, USE_LITE_WIDTH)
    text = {"mask": mask, "encoder_features": encoder_features,
            "encoder_sentence": sentence / sentence.norm(2, -1, keepdim=True)}

    motion = features_to_model_space(features)
    clips = [motion[i].narrow(0, 0, int(frame_counts[i])).narrow(1, 0, int(joint_counts[i])) for i in range(b)]
    x = {"motion": motion, "frame_mask": frame_mask, "joint_mask": joint_mask, "joint_embeddings": embeddings,
         "text": text, "global_items": b}
    if stage == "pose":
        picks = (torch.rand(b, c["pose_frames"]) * frame_counts.to(torch.float).unsqueeze(1)) \
            .floor().to(torch.int64).clamp_max(frames - 1)
        x["motion"] = torch.gather(motion, 1, picks.view(b, -1, 1, 1).expand(b, c["pose_frames"], joints,
                                                                             MODEL_CHANNELS))
        x["frame_mask"] = torch.ones(b, c["pose_frames"], dtype=torch.bool)
    steps = c["noise_steps"]
    x["t"] = (torch.rand(b) * float(steps)).floor().to(torch.int64).clamp_max(steps - 1)
    noises = []
    for i in range(b):
        own = int(joint_counts[i])
        noises.append(F.pad(torch.randn(x["motion"].size(1), own, MODEL_CHANNELS), (0, 0, 0, joints - own)))
    x["noise"] = torch.stack(noises)
    draws = torch.rand(b)
    x["drop_text"] = torch.tensor([float(draws[i]) < c["caption_dropout"] for i in range(b)], dtype=torch.bool)
    return x, clips


# ---- The step and its measurement ----

class Trainee(ScheduledTrainee):
    def __init__(self, c, stage, joints):
        self.stage = stage
        torch.manual_seed(SEED)
        self.x, clips = synthetic_batch(c, stage, joints)
        model = MotionDenoiser(c)
        model.fit_statistics(clips)
        if stage == "motion":
            # Stand-in for a trained pose model (synthetic.cpp synthetic_denoiser), then frozen.
            with torch.no_grad():
                for name, p in model.named_parameters():
                    if model.is_pose_parameter(name):
                        p.add_(torch.randn(p.shape) * POSE_STAND_IN_STD)
                        p.requires_grad_(False)
        super().__init__(c, model, model.trained_parameters(stage))
        self.alpha_bar = alpha_bars(c["noise_steps"])

    def step(self):
        """diffusion/synthetic.cpp synthetic_diffusion_train_step."""
        lr = self.next_rate()
        self.model.train()
        if self.stage == "motion":
            self.model.text.eval()  # the frozen caption encoder reads captions without dropout
        self.optimizer.zero_grad()
        loss = denoising_objective(self.model, self.alpha_bar, self.x, self.stage, self.c["velocity_weight"])
        loss.backward()
        self.optimizer_step(lr)
        return loss.item()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_arguments(parser, "diffusion_pose_cpu.json, diffusion_motion_cpu.json and owo_cpu.json",
                  default_repetitions=3)
    parser.add_argument("--stage", choices=("motion", "pose"), nargs="+", default=["motion", "pose"],
                        help="motion: temporal blocks on the frozen pose model; pose: the pose model (default: both)")
    parser.add_argument("--joints", type=int, nargs="+", default=[22, 100], help="skeleton sizes (default: 22 100)")
    parser.add_argument("--iterations", type=int, nargs="+", default=None,
                        help="timed steps per repetition, one per --joints value (default: 1 each for the motion "
                             "stage, 3 for the pose stage, as bench_diffusion)")
    args = parser.parse_args()
    if args.iterations is not None and len(args.iterations) != len(args.joints):
        parser.error("give one --iterations value per --joints value")
    keep_large_allocations_in_heap()
    configs = {stage: read_config(args.configs, stage) for stage in args.stage}
    settings = []
    for stage in args.stage:
        iterations = args.iterations or [1 if stage == "motion" else 3] * len(args.joints)
        settings += [({"stage": stage, "joints": joints}, count) for joints, count in zip(args.joints, iterations)]
    print_json(run_settings("diffusion", settings,
                            lambda setting: Trainee(configs[setting["stage"]], setting["stage"], setting["joints"]),
                            args))


if __name__ == "__main__":
    main()

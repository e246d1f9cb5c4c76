#!/usr/bin/env python3
"""The evaluator's training step in PyTorch (Python): the peer of bench_evaluator's BM_EvaluatorTrainStep.

A line-by-line re-implementation of the text-motion evaluator of evaluator/src/evaluator.cpp,
motion_encoder.cpp and training.cpp, with layers/src/transformer.cpp and the use-lite text encoder
(text/encoder/src/text_encoder.cpp, 0 layers), both in peer_layers.py: the same modules created in the same
order (so the same torch.manual_seed gives the same initial weights), the same dropout calls in the same order
(so the same masks), the same contrastive loss, and the step of EvaluatorTrainer::step after its batch is made
(zero_grad, backward, the gradient clip, AdamW at the scheduled learning rate) on the synthetic batch of
evaluator/src/synthetic.cpp, drawn with the same torch random calls. The tokenizer's model space comes from
peer_tat_step.py, as the C++ motion encoder reads tat/model_space.h. Its first two losses therefore equal
bench_evaluator's counters loss_step0 / loss_step1 up to float rounding, which scripts/bench.sh checks.

    /usr/bin/python3 benchmarks/peer_evaluator_step.py --expect-parameters N [--joints 22 100] [--iterations 3 1]
        [--threads 1 2] [--repetitions 5]
        [--configs DIR]   # evaluator_cpu.json and owo_cpu.json, as bench_evaluator --configs=DIR
        [--profile-ops DIR]   # one more step per setting under the op profiler, as bench_evaluator --profile_ops=DIR

Prints one JSON object on stdout (per setting: wall-clock and process CPU time per step in ms over the
repetitions, the first losses, parameter count, peak memory of a step); exits 1 when the parameter count
differs from --expect-parameters (the count bench_evaluator reports). Runs with nec's allocator policy and
shares its measurement with the other peers (peer_step.py).
"""
import argparse
import json
import math
import os
import sys

import torch
import torch.nn as nn
import torch.nn.functional as F

from peer_layers import Linear, TextEncoder, TransformerStack, masked_mean, padding_bias, USE_LITE_WIDTH
from peer_step import add_arguments, keep_large_allocations_in_heap, print_json, run_settings, ScheduledTrainee
from peer_tat_step import features_to_model_space, random_features, MODEL_CHANNELS

SEED = 0               # torch.manual_seed before inputs and model, as bench_evaluator
PIECES = 12            # synthetic.h kSyntheticPieces
MIN_PIECES = 4         # synthetic.h kSyntheticMinPieces
LOGIT_SCALE_LIMIT = 100.0  # evaluator.cpp logit_scale


# ---- Configuration (defaults of evaluator/include/nec/evaluator/{motion_encoder,evaluator,training}.h) ----

def read_config(configs):
    with open(os.path.join(configs, "evaluator_cpu.json")) as f:
        raw = json.load(f)
    with open(os.path.join(configs, "owo_cpu.json")) as f:
        embedding_dim = json.load(f)["encoder"]["dim"]
    model = raw.get("model", {})
    motion = model.get("motion", {})
    text = model.get("text", {})
    optimizer = raw.get("optimizer", {})
    backbone, text_layers = text.get("backbone", "pieces"), text.get("layers", 2)
    if backbone != "use-lite" or text_layers != 0 or text.get("piece_memory", False):
        sys.exit(f"peer_evaluator_step: text backbone {backbone!r} with {text_layers} layers is not re-implemented "
                 "(use-lite, 0 layers, no piece_memory only)")
    return {
        "joint_embedding_dim": embedding_dim,
        "dim": motion.get("dim", 128),
        "patch_frames": motion.get("patch_frames", 4),
        "spatial_layers": motion.get("spatial_layers", 1),
        "temporal_layers": motion.get("temporal_layers", 2),
        "heads": motion.get("heads", 4),
        "feedforward": motion.get("feedforward", 256),
        "max_steps": motion.get("max_steps", 64),
        "output_dim": motion.get("output_dim", 128),
        "dropout": motion.get("dropout", 0.1),
        "text": {"dim": text.get("dim", 128), "layers": 0, "output_dim": text.get("output_dim", 128),
                 "dropout": text.get("dropout", 0.1)},
        "initial_temperature": model.get("initial_temperature", 0.07),
        "learning_rate": optimizer.get("learning_rate", 3e-4),
        "final_lr_fraction": optimizer.get("final_lr_fraction", 0.05),
        "warmup_steps": optimizer.get("warmup_steps", 100),
        "weight_decay": optimizer.get("weight_decay", 0.01),
        "grad_clip": optimizer.get("grad_clip", 1.0),
        "steps": raw.get("steps", 3000),
        "batch_size": raw.get("batch_size", 64),
        "window_frames": raw.get("data", {}).get("window_frames", 64),
    }


# ---- The evaluator (motion_encoder.cpp, evaluator.cpp) ----

class MotionEncoder(nn.Module):
    def __init__(self, c):
        super().__init__()
        d = c["dim"]
        self.patch_frames = c["patch_frames"]
        self.patch_in = Linear(c["patch_frames"] * MODEL_CHANNELS, d)
        self.joint_in = Linear(c["joint_embedding_dim"], d)
        self.summary = nn.Parameter(torch.randn(d) * 0.02)
        self.step_positions = nn.Parameter(torch.randn(c["max_steps"], d) * 0.02)
        self.spatial = TransformerStack(d, c["heads"], c["feedforward"], c["dropout"], c["spatial_layers"])
        self.temporal = TransformerStack(d, c["heads"], c["feedforward"], c["dropout"], c["temporal_layers"])
        self.out = Linear(d, c["output_dim"])

    def forward(self, features, joint_mask, frame_mask, joint_embeddings):
        """features (B, T, J, 9), joint_mask (B, J), frame_mask (B, T), joint_embeddings (B, J, E) -> (B, output)."""
        b, t, j = features.shape[:3]
        d, p = self.summary.size(0), self.patch_frames
        steps = (t + p - 1) // p
        real = frame_mask.unsqueeze(2).logical_and(joint_mask.unsqueeze(1))
        model = features_to_model_space(features) * real.unsqueeze(-1).to(features.dtype)
        frames = frame_mask
        if steps * p != t:
            model = F.pad(model, (0, 0, 0, 0, 0, steps * p - t))
            frames = F.pad(frame_mask, (0, steps * p - t))
        patches = model.view(b, steps, p, j, MODEL_CHANNELS).permute(0, 1, 3, 2, 4).reshape(
            b, steps, j, p * MODEL_CHANNELS)
        joints = self.patch_in(patches) + self.joint_in(joint_embeddings).unsqueeze(1)  # (B, S, J, D)
        tokens = torch.cat([self.summary.view(1, 1, 1, d).expand(b, steps, 1, d), joints], 2).reshape(
            b * steps, j + 1, d)
        keep = torch.cat([torch.ones(b, 1, dtype=joint_mask.dtype), joint_mask], 1)
        joint_bias = padding_bias(keep).repeat_interleave(steps, 0)  # (B S, 1, 1, 1 + J)
        summaries = self.spatial(tokens, joint_bias).select(1, 0).view(b, steps, d)
        step_mask = frames.view(b, steps, p).select(2, 0)
        timeline = self.temporal(summaries + self.step_positions.narrow(0, 0, steps).unsqueeze(0),
                                 padding_bias(step_mask))
        return self.out(masked_mean(timeline, step_mask))


class Evaluator(nn.Module):
    def __init__(self, c):
        super().__init__()
        self.motion = MotionEncoder(c)
        self.text = TextEncoder(c["text"])
        self.log_scale = nn.Parameter(torch.tensor(math.log(1.0 / c["initial_temperature"])))

    def logit_scale(self):
        return self.log_scale.exp().clamp_max(LOGIT_SCALE_LIMIT)


def contrastive_loss(motion, text, scale, same):
    """training.cpp contrastive_loss: symmetric InfoNCE, the target of a row spread over its matches."""
    logits = scale * motion.matmul(text.t())
    targets = same.to(logits.dtype)
    rows = targets / targets.sum(1, keepdim=True)
    columns = targets / targets.sum(0, keepdim=True)
    motion_to_text = -(rows * torch.log_softmax(logits, 1)).sum(1).mean()
    text_to_motion = -(columns * torch.log_softmax(logits, 0)).sum(0).mean()
    return 0.5 * (motion_to_text + text_to_motion)


def contrastive_batch_loss(model, x):
    """training.cpp contrastive_batch_loss: motions embedded first, then captions (the dropout draws' order)."""
    motion = F.normalize(model.motion(x["features"], x["joint_mask"], x["frame_mask"], x["joint_embeddings"]), dim=1)
    text = F.normalize(model.text(x["captions"])[0], dim=1)
    return contrastive_loss(motion, text, model.logit_scale(), x["same"])


# ---- Synthetic batch (synthetic.cpp synthetic_contrastive_batch, same draws in the same order) ----

def leading_mask(counts, size):
    return torch.arange(size, dtype=torch.long).unsqueeze(0) < counts.unsqueeze(1)


def masked(x, mask):
    return x * mask.unsqueeze(-1).to(x.dtype)


def synthetic_batch(batch, frames, joints, embedding_dim):
    joint_counts = torch.randint(joints - joints // 4, joints + 1, (batch,), dtype=torch.long)
    joint_counts[0] = joints
    x = {"joint_mask": leading_mask(joint_counts, joints),
         "frame_mask": leading_mask(torch.randint(frames // 2, frames + 1, (batch,), dtype=torch.long), frames)}
    real = x["frame_mask"].unsqueeze(2).logical_and(x["joint_mask"].unsqueeze(1))
    x["features"] = random_features(batch, frames, joints) * real.unsqueeze(-1).to(torch.float)
    x["joint_embeddings"] = masked(torch.randn(batch, joints, embedding_dim), x["joint_mask"])
    # The per-piece features are drawn as synthetic.cpp draws them, though 0 text layers read only the sentence.
    piece_mask = leading_mask(torch.randint(MIN_PIECES, PIECES + 1, (batch,), dtype=torch.long), PIECES)
    x["captions"] = {"mask": piece_mask,
                     "encoder_features": masked(torch.randn(batch, PIECES, USE_LITE_WIDTH), piece_mask),
                     "encoder_sentence": F.normalize(torch.randn(batch, USE_LITE_WIDTH), dim=1)}
    caption_ids = torch.randint(0, 4 * batch, (batch,), dtype=torch.long)
    x["same"] = caption_ids.unsqueeze(1) == caption_ids.unsqueeze(0)
    return x


# ---- The step and its measurement ----

class Trainee(ScheduledTrainee):
    def __init__(self, c, joints):
        torch.manual_seed(SEED)
        self.x = synthetic_batch(c["batch_size"], c["window_frames"], joints, c["joint_embedding_dim"])
        model = Evaluator(c)
        super().__init__(c, model, model.parameters())

    def step(self):
        """synthetic.cpp synthetic_evaluator_train_step: EvaluatorTrainer::step after its batch is made."""
        lr = self.next_rate()
        self.model.train()
        self.optimizer.zero_grad()
        loss = contrastive_batch_loss(self.model, self.x)
        loss.backward()
        self.optimizer_step(lr)
        return loss.item()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_arguments(parser, "evaluator_cpu.json and owo_cpu.json", default_repetitions=5)
    parser.add_argument("--joints", type=int, nargs="+", default=[22, 100], help="skeleton sizes (default: 22 100)")
    parser.add_argument("--iterations", type=int, nargs="+", default=[3, 1],
                        help="timed steps per repetition, one per --joints value (default: 3 1, as bench_evaluator)")
    args = parser.parse_args()
    if len(args.iterations) != len(args.joints):
        parser.error("give one --iterations value per --joints value")
    keep_large_allocations_in_heap()
    c = read_config(args.configs)
    settings = [({"joints": joints}, iterations) for joints, iterations in zip(args.joints, args.iterations)]
    print_json(run_settings("evaluator", settings, lambda setting: Trainee(c, setting["joints"]), args))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The GPT's training step in PyTorch (Python): the peer of bench_gpt's BM_GptTrainStep.

A line-by-line re-implementation of the text-to-token GPT of gpt/src/model.cpp
with its use-lite caption head (text/encoder/src/text_encoder.cpp,
layers/src/transformer.cpp, in peer_layers.py): the same modules created in
the same order (so the same torch.manual_seed gives the same initial weights),
the same dropout and corruption draws in the same order, the same loss
(gpt/src/training.cpp gpt_loss), and the step of GptTrainer::step after its
batch is made and its captions read (zero_grad, condition, token corruption,
forward, loss, backward, the global-norm clip of train/optimizer.cpp, AdamW at
the scheduled learning rate) on the synthetic batch of gpt/src/synthetic.cpp,
drawn with the same torch random calls. Its first two losses therefore equal
bench_gpt's counters loss_step0 / loss_step1 up to float rounding
(tests/test_gpt_peer_step.cpp holds them). Linear layers compute as LibTorch's
do (peer_layers.Linear), so that the sums are the same; what remains is the
order in which layers::batched_matmul sums the text encoder's attention
products.

    /usr/bin/python3 benchmarks/peer_gpt_step.py --expect-parameters N [--iterations 3] [--threads 1 2]
        [--repetitions 5]
        [--configs DIR]   # gpt_cpu.json, tat_cpu.json and owo_cpu.json, as bench_gpt --configs=DIR
        [--profile-ops DIR]   # one more step per thread count under the op profiler, as bench_gpt --profile_ops=DIR

Prints one JSON object on stdout (per thread count: wall-clock and process
CPU time per step in ms over the repetitions, the first losses, parameter
count, peak memory of a step); exits 1 when the parameter count differs from
--expect-parameters (the count bench_gpt reports). Runs with nec's allocator
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

from peer_layers import Linear, TextEncoder, padding_bias, MASKED_SCORE, USE_LITE_WIDTH
from peer_step import add_arguments, keep_large_allocations_in_heap, print_json, run_settings, ScheduledTrainee

SEED = 0                   # torch.manual_seed before the batch and the model, as bench_gpt
PREFIX_TOKENS = 2          # model.cpp kPrefixTokens: sentence, skeleton
MIN_PIECES, MAX_PIECES = 4, 16           # gpt/synthetic.h kSyntheticMinPieces, kSyntheticMaxPieces
MIN_CLIP_STEPS, MAX_CLIP_STEPS = 15, 60  # gpt/synthetic.h kSyntheticMinClipSteps, kSyntheticMaxClipSteps


# ---- Configuration (defaults of gpt/include/nec/gpt/{model,training}.h, text_encoder.h) ----

def read_config(configs):
    def load(name):
        with open(os.path.join(configs, name)) as f:
            return json.load(f)
    raw = load("gpt_cpu.json")
    quantizer = load("tat_cpu.json").get("model", {}).get("quantizer", {})
    model = raw.get("model", {})
    text = model.get("text", {})
    optimizer = raw.get("optimizer", {})
    backbone = text.get("backbone", "pieces")
    if backbone != "use-lite" or text.get("layers", 2) < 1:
        sys.exit(f"peer_gpt_step: text backbone {backbone!r} with {text.get('layers', 2)} layers is not "
                 "re-implemented (use-lite with layers >= 1 only)")
    return {
        # As `nec train gpt` sets them from the tokenizer: its quantizer and its OwO encoder's width.
        "codebook_layers": quantizer.get("layers", 4),
        "codebook_size": quantizer.get("codebook_size", 256),
        "skeleton_dim": load("owo_cpu.json")["encoder"]["dim"],
        "dim": model.get("dim", 192),
        "layers": model.get("layers", 4),
        "heads": model.get("heads", 4),
        "feedforward": model.get("feedforward", 768),
        "max_steps": model.get("max_steps", 64),
        "dropout": model.get("dropout", 0.1),
        "text": {
            "dim": text.get("dim", 128),
            "layers": text.get("layers", 2),
            "heads": text.get("heads", 4),
            "feedforward": text.get("feedforward", 256),
            "max_pieces": text.get("max_pieces", 48),
            "output_dim": text.get("output_dim", 128),
            "dropout": text.get("dropout", 0.1),
            "piece_dropout": text.get("piece_dropout", 0.1),
        },
        "learning_rate": optimizer.get("learning_rate", 3e-4),
        "final_lr_fraction": optimizer.get("final_lr_fraction", 0.05),
        "warmup_steps": optimizer.get("warmup_steps", 100),
        "weight_decay": optimizer.get("weight_decay", 0.01),
        "grad_clip": optimizer.get("grad_clip", 1.0),
        "token_keep": raw.get("token_keep", 0.8),
        "caption_dropout": raw.get("caption_dropout", 0.1),
        "steps": raw.get("steps", 3000),
        "batch_size": raw.get("batch_size", 32),
    }


# ---- The GPT (model.cpp) ----

class GptBlock(nn.Module):
    """Pre-norm causal self-attention, cross-attention to the caption, FFN."""

    def __init__(self, c):
        super().__init__()
        d = c["dim"]
        self.heads = c["heads"]
        self.self_norm = nn.LayerNorm(d)
        self.qkv = Linear(d, 3 * d)
        self.self_out = Linear(d, d)
        self.cross_norm = nn.LayerNorm(d)
        self.query = Linear(d, d)
        self.memory_kv = Linear(d, 2 * d)
        self.cross_out = Linear(d, d)
        self.ffn_norm = nn.LayerNorm(d)
        self.ffn_in = Linear(d, c["feedforward"])
        self.ffn_out = Linear(c["feedforward"], d)
        self.dropout = nn.Dropout(c["dropout"])

    def split_heads(self, x):
        """(B, N, D) -> (B, H, N, Dh)"""
        return x.view(x.size(0), x.size(1), self.heads, x.size(2) // self.heads).transpose(1, 2)

    def memory_keys_values(self, memory):
        keys, values = self.memory_kv(memory).chunk(2, -1)
        return self.split_heads(keys), self.split_heads(values)

    def forward(self, x, memory_keys, memory_values, memory_bias):
        """Teacher forcing (an empty cache): x (B, N, D) -> (B, N, D)."""
        b, n, d = x.shape
        scale = 1.0 / math.sqrt(d // self.heads)
        q, k, v = (self.split_heads(part) for part in self.qkv(self.self_norm(x)).chunk(3, -1))
        scores = torch.matmul(q, k.transpose(-1, -2)) * scale
        if n > 1:
            scores = scores.masked_fill(torch.ones(n, n, dtype=torch.bool).triu(1), MASKED_SCORE)
        attended = torch.matmul(torch.softmax(scores, -1), v).transpose(1, 2).reshape(b, n, d)
        y = x + self.dropout(self.self_out(attended))
        cq = self.split_heads(self.query(self.cross_norm(y)))
        cross_scores = torch.matmul(cq, memory_keys.transpose(-1, -2)) * scale + memory_bias
        read = torch.matmul(torch.softmax(cross_scores, -1), memory_values).transpose(1, 2).reshape(b, n, d)
        y = y + self.dropout(self.cross_out(read))
        return y + self.ffn_out(self.dropout(F.gelu(self.ffn_in(self.ffn_norm(y)))))


class TokenGpt(nn.Module):
    def __init__(self, c):
        super().__init__()
        self.c = c
        d, k, r = c["dim"], c["codebook_size"], c["codebook_layers"]
        self.text = TextEncoder(c["text"])
        self.sentence_in = Linear(c["text"]["output_dim"], d)
        self.pieces_in = Linear(c["text"]["dim"], d)
        self.skeleton_in = Linear(3 * c["skeleton_dim"] + 1, d)  # model.h skeleton_feature_width
        self.null_sentence = nn.Parameter(torch.randn(d) * 0.02)
        self.null_piece = nn.Parameter(torch.randn(d) * 0.02)
        self.code_embeddings = nn.ModuleList([nn.Embedding(k, d) for _ in range(r)])
        self.positions = nn.Parameter(torch.randn(PREFIX_TOKENS + c["max_steps"], d) * 0.02)
        self.dropout = nn.Dropout(c["dropout"])
        self.blocks = nn.ModuleList([GptBlock(c) for _ in range(c["layers"])])
        self.norm = nn.LayerNorm(d)
        self.depth_embeddings = nn.ModuleList([nn.Embedding(k, d) for _ in range(1, r)])
        self.depth_hidden = Linear(d, d)
        self.depth_norm = nn.LayerNorm(d)
        self.heads = nn.ModuleList([Linear(d, k + 1 if layer == 0 else k) for layer in range(r)])

    def condition(self, captions, skeleton_features, drop_text):
        """-> prefix (B, 2, D), memory (B, P, D), memory_bias (B, 1, 1, P)."""
        encoded_sentence, encoded_features, mask = self.text(captions)
        b = skeleton_features.size(0)
        sentence = self.sentence_in(encoded_sentence)
        memory = self.pieces_in(encoded_features)
        drop = drop_text.view(b, 1)
        sentence = torch.where(drop, self.null_sentence.expand_as(sentence), sentence)
        # A dropped caption keeps one piece, the null one, at position 0.
        first = torch.zeros_like(mask)
        first.select(1, 0).fill_(True)
        drop_pieces = drop.expand_as(mask)
        mask = torch.where(drop_pieces, first, mask)
        null_row = first.unsqueeze(-1).to(memory.dtype) * self.null_piece
        memory = torch.where(drop_pieces.unsqueeze(-1), null_row, memory)
        prefix = torch.stack([sentence, self.skeleton_in(skeleton_features)], 1)
        return prefix, memory, padding_bias(mask)

    def embed_steps(self, codes):
        x = self.positions.narrow(0, PREFIX_TOKENS, codes.size(1)).unsqueeze(0)
        for layer, embedding in enumerate(self.code_embeddings):
            x = x + embedding(codes.select(2, layer))
        return x

    def forward(self, condition, inputs, targets):
        """inputs (B, S, R), targets (B, S + 1, R) -> first (B, S + 1, K + 1), rest (B, S + 1, R - 1, K)."""
        prefix, memory, memory_bias = condition
        memory_keys_values = [block.memory_keys_values(memory) for block in self.blocks]
        s = inputs.size(1)
        x = prefix + self.positions.narrow(0, 0, PREFIX_TOKENS).unsqueeze(0)
        if s > 0:
            x = torch.cat([x, self.embed_steps(inputs)], 1)
        y = self.dropout(x)
        for block, (keys, values) in zip(self.blocks, memory_keys_values):
            y = block(y, keys, values, memory_bias)
        h = self.norm(y).narrow(1, PREFIX_TOKENS - 1, s + 1)
        k = self.c["codebook_size"]
        first = self.heads[0](self.depth_norm(F.gelu(self.depth_hidden(h))))
        # Padding (-1) and the end code read as code 0; their targets are not scored.
        given = targets.clamp(0, k - 1)
        depth = h
        rest = []
        for layer in range(1, self.c["codebook_layers"]):
            depth = depth + self.depth_embeddings[layer - 1](given.select(2, layer - 1))
            rest.append(self.heads[layer](self.depth_norm(F.gelu(self.depth_hidden(depth)))))
        rest = torch.stack(rest, 2) if rest else torch.zeros(h.size(0), s + 1, 0, k)
        return first, rest


def gpt_loss(first, rest, targets, global_items):
    """training.cpp gpt_loss -> (loss, layer-0 accuracy)."""
    b, n, k = targets.size(0), targets.size(1), rest.size(3)
    first_target = targets.select(2, 0)
    first_scored = first_target >= 0
    first_ce = F.cross_entropy(first.reshape(b * n, k + 1), first_target.clamp_min(0).reshape(b * n),
                               reduction="none").view(b, n)
    total = (first_ce * first_scored).sum(1)
    count = first_scored.sum(1).to(torch.float32)
    if rest.size(2) > 0:
        rest_target = targets.narrow(2, 1, targets.size(2) - 1)
        rest_scored = rest_target >= 0
        rest_ce = F.cross_entropy(rest.reshape(-1, k), rest_target.clamp_min(0).reshape(-1),
                                  reduction="none").view(rest_target.shape)
        total = total + (rest_ce * rest_scored).sum((1, 2))
        count = count + rest_scored.sum((1, 2)).to(torch.float32)
    loss = (total / count.clamp_min(1.0)).sum() / float(global_items)
    right = (first.argmax(2) == first_target) & first_scored
    accuracy = right.sum().item() / max(1.0, first_scored.sum().item())
    return loss, accuracy


# ---- Synthetic batch (gpt/src/synthetic.cpp synthetic_gpt_batch, same draws in the same order) ----

def synthetic_gpt_batch(c):
    b, r, k, window = c["batch_size"], c["codebook_layers"], c["codebook_size"], c["max_steps"] - 1
    codes = torch.randint(0, k, (b, window + 1, r))
    clip_steps = torch.randint(MIN_CLIP_STEPS, MAX_CLIP_STEPS + 1, (b,))
    lengths = clip_steps.clamp_max(window)
    starts = (torch.rand(b) * (clip_steps - lengths + 1).to(torch.float32)).floor().to(torch.long)
    reaches_end = (starts + lengths == clip_steps).view(b, 1, 1)
    s = lengths.max().item()
    step = torch.arange(s + 1).view(1, s + 1, 1)
    length = lengths.view(b, 1, 1)
    crop = codes.narrow(1, 0, s + 1)
    x = {"inputs": crop.narrow(1, 0, s) * (step.narrow(1, 0, s) < length)}
    end_codes = torch.full((r,), -1, dtype=torch.long)
    end_codes.select(0, 0).fill_(k)
    x["targets"] = torch.where((step == length).logical_and(reaches_end), end_codes.expand_as(crop),
                               torch.where(step <= length, crop, torch.full_like(crop, -1)))
    x["drop_text"] = torch.rand(b) < c["caption_dropout"]
    x["skeleton_features"] = torch.randn(b, 3 * c["skeleton_dim"] + 1)
    pieces = torch.randint(MIN_PIECES, MAX_PIECES + 1, (b,))
    p = pieces.max().item()
    mask = torch.arange(p).view(1, p) < pieces.view(b, 1)
    features = torch.randn(b, p, USE_LITE_WIDTH) * mask.unsqueeze(-1).to(torch.float32)
    sentence = torch.randn(b, USE_LITE_WIDTH)
    # Not F.normalize: its norm goes through linalg.vector_norm, LibTorch's normalize through norm.
    x["captions"] = {"mask": mask, "encoder_features": features,
                     "encoder_sentence": sentence * sentence.square().sum(1, keepdim=True).rsqrt()}
    return x


# ---- The step and its measurement ----

class Trainee(ScheduledTrainee):
    def __init__(self, c):
        torch.manual_seed(SEED)
        self.x = synthetic_gpt_batch(c)
        model = TokenGpt(c)
        super().__init__(c, model, model.parameters())

    def step(self):
        """synthetic_gpt_train_step: GptTrainer::step after its batch is made and its captions read."""
        lr = self.next_rate()
        self.model.train()
        self.optimizer.zero_grad()
        x = self.x
        condition = self.model.condition(x["captions"], x["skeleton_features"], x["drop_text"])
        inputs = x["inputs"]
        if self.c["token_keep"] < 1:
            # T2M-GPT's corruption: an input step's codes are replaced by random ones.
            replace = torch.rand(inputs.size(0), inputs.size(1), 1) >= self.c["token_keep"]
            inputs = torch.where(replace, torch.randint_like(inputs, self.c["codebook_size"]), inputs)
        first, rest = self.model(condition, inputs, x["targets"])
        loss, _ = gpt_loss(first, rest, x["targets"], inputs.size(0))
        loss.backward()
        value = loss.item()
        self.optimizer_step(lr)
        return value


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_arguments(parser, "gpt_cpu.json, tat_cpu.json and owo_cpu.json", default_repetitions=5)
    parser.add_argument("--iterations", type=int, default=3,
                        help="timed steps per repetition (default: 3, as bench_gpt)")
    args = parser.parse_args()
    keep_large_allocations_in_heap()
    c = read_config(args.configs)
    print_json(run_settings("gpt", [({}, args.iterations)], lambda setting: Trainee(c), args))


if __name__ == "__main__":
    main()

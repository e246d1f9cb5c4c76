"""The layers the training-step peers (benchmarks/peer_*_step.py) share: layers/src/transformer.cpp and the use-lite
caption head of text/encoder/src/text_encoder.cpp, built in the C++ order (so the same torch.manual_seed gives the
same initial weights) and computed as LibTorch computes them (so the same sums)."""
import math

import torch
import torch.nn as nn
import torch.nn.functional as F

MASKED_SCORE = -1e9   # layers/transformer.h kMaskedScore
USE_LITE_WIDTH = 512  # text_encoder.h kUseLiteWidth


class Linear(nn.Linear):
    """nn.Linear computed as LibTorch's torch::nn::Linear computes it: addmm for (N, in) inputs, else matmul and
    then the bias added (without a bias, matmul alone). Python's F.linear folds the bias of a contiguous 3-d input
    into one addmm, which rounds differently."""

    def forward(self, x):
        if self.bias is None:
            return x.matmul(self.weight.t())
        if x.dim() == 2:
            return torch.addmm(self.bias, x, self.weight.t())
        out = x.matmul(self.weight.t())
        out += self.bias
        return out


def padding_bias(mask):
    """(B, N) bool, true for real tokens -> (B, 1, 1, N) additive bias over the keys."""
    bias = torch.zeros(mask.shape).masked_fill_(mask.logical_not(), MASKED_SCORE)
    return bias.view(mask.size(0), 1, 1, mask.size(1))


def masked_mean(x, mask):
    """x (B, N, D), mask (B, N) bool -> (B, D)."""
    weights = mask.to(x.dtype).unsqueeze(-1)
    return (x * weights).sum(1) / weights.sum(1).clamp_min(1.0)


def multi_head_attention(qkv, heads, bias=None):
    """qkv (B, N, 3 D), bias None or broadcast to (B, H, N, N) -> (B, N, D): one copy into (3, B H, N, Dh) and the
    keys transposed in memory, then bmm, as layers::multi_head_attention."""
    b, n, d = qkv.size(0), qkv.size(1), qkv.size(2) // 3
    head_dim = d // heads
    split = qkv.view(b, n, 3, heads, head_dim).permute(2, 0, 3, 1, 4).reshape(3, b * heads, n, head_dim)
    keys = split[1].transpose(1, 2).contiguous()
    scores = torch.bmm(split[0] * (1.0 / math.sqrt(head_dim)), keys).view(b, heads, n, n)
    if bias is not None:
        scores = scores + bias
    mixed = torch.bmm(torch.softmax(scores, -1).view(b * heads, n, n), split[2])  # (B H, N, Dh)
    return mixed.view(b, heads, n, head_dim).permute(0, 2, 1, 3).reshape(b, n, d)


class TransformerLayer(nn.Module):
    """x + dropout(MHA(LN(x))), then + FFN(LN(x)) with dropout after the GELU."""

    def __init__(self, dim, heads, feedforward, dropout):
        super().__init__()
        self.heads = heads
        self.attention_norm = nn.LayerNorm(dim)
        self.qkv = Linear(dim, 3 * dim)
        self.out = Linear(dim, dim)
        self.ffn_norm = nn.LayerNorm(dim)
        self.ffn_in = Linear(dim, feedforward)
        self.ffn_out = Linear(feedforward, dim)
        self.dropout = nn.Dropout(dropout)

    def forward(self, x, bias):
        mixed = multi_head_attention(self.qkv(self.attention_norm(x)), self.heads, bias)
        attended = x + self.dropout(self.out(mixed))
        return attended + self.ffn_out(self.dropout(F.gelu(self.ffn_in(self.ffn_norm(attended)))))


class TransformerStack(nn.Module):
    def __init__(self, dim, heads, feedforward, dropout, layers):
        super().__init__()
        self.layers = nn.ModuleList([TransformerLayer(dim, heads, feedforward, dropout) for _ in range(layers)])
        self.norm = nn.LayerNorm(dim)

    def forward(self, x, bias):
        for layer in self.layers:
            x = layer(x, bias)
        return self.norm(x)


class TextEncoder(nn.Module):
    """The caption head on the use-lite backbone (no piece_memory), t the model.text config: with layers > 0 a
    transformer over the sentence encoder's piece features, with 0 the sentence vector through one GELU layer."""

    def __init__(self, t):
        super().__init__()
        self.t = t
        self.input = Linear(USE_LITE_WIDTH, t["dim"])
        if t["layers"] > 0:
            self.encoder_sentence = Linear(USE_LITE_WIDTH, t["output_dim"])
            self.positions = nn.Parameter(torch.randn(t["max_pieces"], t["dim"]) * 0.02)
            self.transformer = TransformerStack(t["dim"], t["heads"], t["feedforward"], t["dropout"], t["layers"])
        self.sentence = Linear(t["dim"], t["output_dim"])

    def dropped_encoder_features(self, features):
        if not self.training or self.t["piece_dropout"] == 0:
            return features
        kept = torch.rand(features.size(0), features.size(1), 1) >= self.t["piece_dropout"]
        return features * kept.to(features.dtype)

    def forward(self, captions):
        """-> sentence (B, output_dim), features (B, P, dim), mask (B, P), as TextEncoding."""
        if self.t["layers"] == 0:
            hidden = F.gelu(self.input(F.dropout(captions["encoder_sentence"], self.t["dropout"], self.training)))
            return self.sentence(hidden), hidden.unsqueeze(1), torch.ones(hidden.size(0), 1, dtype=torch.bool)
        mask = captions["mask"]
        tokens = self.input(self.dropped_encoder_features(captions["encoder_features"])) + \
            self.positions.narrow(0, 0, mask.size(1)).unsqueeze(0)
        features = self.transformer(tokens, padding_bias(mask))
        sentence = self.sentence(masked_mean(features, mask)) + self.encoder_sentence(captions["encoder_sentence"])
        return sentence, features, mask

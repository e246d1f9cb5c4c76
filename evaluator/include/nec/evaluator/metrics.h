// Text-motion evaluation metrics on embeddings: R-Precision and MM-Dist, FID,
// Diversity and Multimodality (Guo et al. 2022, as T2M and MoMask compute them),
// Coverage and Novelty AUC (How to Move Your Dragon, appendix C) and jitter.
// No torch: the caller runs the encoders and passes the embeddings here.
//
//   Embeddings text = ..., motion = ...;             // (N, D), row i of each is a matched pair
//   RPrecision r = r_precision(text, motion);        // batches of 32, 20 repeats
//   // r.top_k[0].mean = R@1, r.top_k[0].half_width its 95% interval, r.mm_dist = MM-Dist
//   double f = fid(real_motion, generated_motion);   // (N1, D), (N2, D)
//   double d = diversity(generated_motion);          // 300 random pairs
//   CoverageNovelty c = coverage_novelty(reference_windows, generated_windows);
//   // c.coverage_auc, c.novelty_auc
//
// Everything random is drawn from SplitMix64 (motion/random.h): the same seed
// gives the same numbers with any standard library. Invalid input (empty sets,
// mismatched rows or columns, too few items, non-finite values) throws
// std::invalid_argument.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace nec::evaluator {

using Embeddings = Eigen::MatrixXd;  // (N, D): one item per row

// The rows `rows` of `all`, in that order. (rows.size(), D)
Embeddings rows_of(const Embeddings& all, const std::vector<int>& rows);

// A mean over repeats with its 95% confidence half width (T2M's "± x").
struct Interval {
  double mean = 0.0;
  double half_width = 0.0;  // 1.96 * std / sqrt(repeats), std with the n - 1 denominator; 0 for one repeat
};
// Throws when `values` is empty.
Interval interval_of(const std::vector<double>& values);

// ---- R-Precision and MM-Dist -------------------------------------------------

struct RPrecisionOptions {
  int batch_size = 32;  // texts ranked against the motions of their batch, e.g. 32 (T2M)
  int repeats = 20;     // reshuffles into batches, e.g. 20 (T2M's replications)
  uint64_t seed = 0;    // repeat r shuffles with SplitMix64(mix64(seed ^ mix64(r)))
  int top_k = 3;        // R@1 .. R@top_k are reported, e.g. 3; at most batch_size

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

struct RPrecision {
  std::vector<Interval> top_k;              // (top_k) [0] = R@1, [1] = R@2, ...
  Interval mm_dist;                         // mean Euclidean distance of the matched pairs
  int batches_per_repeat = 0;               // full batches; the incomplete rest of a repeat is dropped
  std::vector<std::string> skipped_groups;  // r_precision_within_groups: groups smaller than batch_size, sorted
};

// One repeat: the N items are shuffled, cut into batches of batch_size (the
// incomplete last batch dropped); each text is ranked by Euclidean distance
// against the batch's motions. Ties: a matched motion at equal distance with e
// others, s others strictly closer, counts (k - s) / (e + 1) clamped to [0, 1]
// towards R@k, its chance of being in the top k when ties are broken at random;
// so identical embeddings give chance, k / batch_size, not 1.
// text, motion: (N, D) with N >= batch_size.
RPrecision r_precision(const Embeddings& text, const Embeddings& motion, const RPrecisionOptions& options = {});

// The same with batches cut within each group ("within plan"): every group's
// items are shuffled and cut into batches of that group only, groups in name
// order; a group smaller than batch_size gives no batch and is listed in
// skipped_groups. groups: (N) one label per row. Throws when no group has
// batch_size items.
RPrecision r_precision_within_groups(const Embeddings& text, const Embeddings& motion,
                                     const std::vector<std::string>& groups, const RPrecisionOptions& options = {});

// R@k of a ranking by chance: k / batch_size, for 1 <= k <= batch_size.
double r_precision_chance(int k, int batch_size);

// ---- FID -------------------------------------------------------------------

// A Gaussian fitted to embeddings.
struct Gaussian {
  Eigen::VectorXd mean;        // (D)
  Eigen::MatrixXd covariance;  // (D, D), n - 1 denominator
};
// embeddings: (N, D) with N >= 2.
Gaussian fit_gaussian(const Embeddings& embeddings);

// The principal square root of a symmetric positive semi-definite matrix (D, D),
// by eigendecomposition; negative eigenvalues (rounding) count as 0.
Eigen::MatrixXd symmetric_sqrt(const Eigen::MatrixXd& matrix);

// ||mean1 - mean2||^2 + tr(cov1 + cov2 - 2 (cov1 cov2)^(1/2)), with the trace of
// (cov1 cov2)^(1/2) taken as tr(sqrt(sqrt(cov1) cov2 sqrt(cov1))), which is
// symmetric PSD, so no complex square root is needed. Rounding below 0 returns 0.
// mean: (D), cov: (D, D) symmetric PSD.
double frechet_distance(const Eigen::VectorXd& mean1, const Eigen::MatrixXd& cov1, const Eigen::VectorXd& mean2,
                        const Eigen::MatrixXd& cov2);

// The Fréchet distance between Gaussians fitted to a (N1, D) and b (N2, D), N1, N2 >= 2.
double fid(const Embeddings& a, const Embeddings& b);

// ---- Diversity and Multimodality ---------------------------------------------

// Two index lists of `pairs` rows each (first[i], second[i] is a pair), drawn
// like Guo et al.'s np.random.choice(rows, pairs, replace=False): without
// replacement within a list when rows >= pairs, with replacement when there are
// fewer rows than pairs. A pair may join a row with itself (distance 0), as in Guo.
// Drawn from SplitMix64(mix64(seed)): the first list, then the second.
struct IndexPairs {
  std::vector<int> first;   // (pairs)
  std::vector<int> second;  // (pairs)
};
IndexPairs draw_pairs(int rows, int pairs, uint64_t seed);

struct DiversityOptions {
  int pairs = 300;    // random pairs of rows, e.g. 300 (T2M)
  uint64_t seed = 0;  // draw_pairs(rows, pairs, seed)

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};
// Mean Euclidean distance of draw_pairs(N, pairs, seed); embeddings: (N, D), N >= 2.
double diversity(const Embeddings& embeddings, const DiversityOptions& options = {});

struct MultimodalityOptions {
  int pairs = 10;     // random pairs of samples per caption, e.g. 10 (T2M)
  uint64_t seed = 0;  // caption c draws draw_pairs(S_c, pairs, mix64(seed ^ mix64(c)))

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};
// samples_per_caption: (C) of (S_c, D), the S_c >= 2 motions generated for
// caption c, e.g. 30. The mean distance of each caption's pairs, averaged over
// captions. Unlike Guo et al. (one index list for all captions), every caption
// draws its own pairs, so S_c may differ between captions.
double multimodality(const std::vector<Embeddings>& samples_per_caption, const MultimodalityOptions& options = {});

// ---- Coverage and Novelty (Dragon eqs. 8-10) ----------------------------------

// F_w = min(L_x, L_x̂, F): the window both motions can give, F = 90 in Dragon.
int window_length(int reference_frames, int generated_frames, int max_window);
// First frames of the windows: 0, stride, 2 stride, ... while start + window <= frames.
// stride 1 gives all frames - window + 1 windows of eq. 8.
std::vector<int> window_starts(int frames, int window, int stride);

struct CoverageNoveltyOptions {
  int thresholds = 101;  // θ values evenly spaced over [0, 1], both ends included, e.g. 101 (steps of 0.01)

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

struct CoverageNovelty {
  std::vector<double> thresholds;  // (thresholds) θ
  std::vector<double> coverage;    // (thresholds) fraction of reference windows whose best cosine to a generated window is > θ
  std::vector<double> novelty;     // (thresholds) fraction of generated windows with 1 - best cosine to a reference window > θ
  double coverage_auc = 0.0;       // trapezoid area under coverage over θ in [0, 1]
  double novelty_auc = 0.0;        // the same for novelty
};

// reference_windows: (Nr, D), generated_windows: (Ng, D), one embedded window per
// row (the caller cuts them with window_length and window_starts). A zero
// vector has cosine 0 with everything.
CoverageNovelty coverage_novelty(const Embeddings& reference_windows, const Embeddings& generated_windows,
                                 const CoverageNoveltyOptions& options = {});

// ---- Smoothness --------------------------------------------------------------

// Mean over frames and joints of the norm of the third finite difference of the
// joint positions times fps^3: the jerk in position units / s^3 (normalize
// positions, e.g. by the skeleton's diameter, before comparing rigs).
// positions: (T, J, 3) world joint positions, row-major, T >= 4.
double jitter(const std::vector<double>& positions, int frames, int joints, double fps);
double jitter(const std::vector<float>& positions, int frames, int joints, double fps);

}  // namespace nec::evaluator

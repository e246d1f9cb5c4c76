// Evaluation metrics on constructed embeddings whose answer is known: hand
// computed intervals, R-Precision on separated / independent / tied points,
// FID against closed forms, Diversity and Multimodality on regular simplices,
// Coverage and Novelty on vectors of known cosine, jitter of polynomial paths.
#include "nec/evaluator/metrics.h"
#include "nec/motion/random.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <stdexcept>

namespace nec::evaluator {
namespace {

// (rows, cols) uniform in [-1, 1).
Embeddings random_embeddings(int rows, int cols, uint64_t seed) {
  SplitMix64 random(mix64(seed));
  Embeddings embeddings(rows, cols);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) embeddings(r, c) = random.uniform(-1.0, 1.0);
  }
  return embeddings;
}

// (size, size) orthogonal, from the QR decomposition of a random matrix.
Eigen::MatrixXd random_rotation(int size, uint64_t seed) {
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(random_embeddings(size, size, seed)).householderQ();
  return q;
}

// (size, size) symmetric positive definite.
Eigen::MatrixXd random_spd(int size, uint64_t seed) {
  const Eigen::MatrixXd a = random_embeddings(size, size, seed);
  return a * a.transpose() + 0.5 * Eigen::MatrixXd::Identity(size, size);
}

// (rows, rows): rows at the vertices of a regular simplex, every distinct pair at `distance`.
Embeddings simplex(int rows, double distance) {
  return Eigen::MatrixXd::Identity(rows, rows) * (distance / std::sqrt(2.0));
}

double max_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).cwiseAbs().maxCoeff(); }

std::string message_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

// ---- Interval ----------------------------------------------------------------

TEST(IntervalOf, HandComputedMeanAndHalfWidth) {
  // {1, 2, 3, 4}: mean 2.5, sample variance (2.25 + 0.25 + 0.25 + 2.25) / 3 = 5 / 3.
  const Interval interval = interval_of({1.0, 2.0, 3.0, 4.0});
  const double half_width = 1.96 * std::sqrt(5.0 / 3.0) / 2.0;
  EXPECT_NEAR(interval.mean, 2.5, 1e-15) << "difference " << interval.mean - 2.5;
  EXPECT_NEAR(interval.half_width, half_width, 1e-15) << "difference " << interval.half_width - half_width;
}

TEST(IntervalOf, OneRepeatHasZeroWidthAndNoneThrows) {
  const Interval one = interval_of({0.7});
  EXPECT_EQ(one.mean, 0.7);
  EXPECT_EQ(one.half_width, 0.0);
  EXPECT_THROW(interval_of({}), std::invalid_argument);
}

// ---- R-Precision ---------------------------------------------------------------

TEST(RPrecision, MatchedPairsAtTheSamePointGiveOneAndZeroDistance) {
  const Embeddings points = random_embeddings(640, 16, 1);
  const RPrecision result = r_precision(points, points);
  ASSERT_EQ(result.top_k.size(), 3u);
  EXPECT_EQ(result.batches_per_repeat, 20);
  for (const Interval& r : result.top_k) {
    EXPECT_EQ(r.mean, 1.0);
    EXPECT_EQ(r.half_width, 0.0);
  }
  EXPECT_EQ(result.mm_dist.mean, 0.0);
  EXPECT_TRUE(result.skipped_groups.empty());
}

TEST(RPrecision, IndependentTextAndMotionAreAtChance) {
  // 20 repeats x 640 texts: the standard error of R@3 is about 0.003, so 0.015 is 5 of them.
  const RPrecision result = r_precision(random_embeddings(640, 16, 2), random_embeddings(640, 16, 3));
  for (int k = 1; k <= 3; ++k) {
    const double chance = r_precision_chance(k, 32);
    EXPECT_NEAR(result.top_k[k - 1].mean, chance, 0.015) << "R@" << k << " difference " << result.top_k[k - 1].mean - chance;
    EXPECT_GT(result.top_k[k - 1].half_width, 0.0);
  }
  // Two independent uniform points of [-1, 1]^16: mean distance about sqrt(16 * 2 / 3) = 3.27.
  EXPECT_NEAR(result.mm_dist.mean, 3.27, 0.1) << "difference " << result.mm_dist.mean - 3.27;
}

TEST(RPrecision, MatchedMotionFarthestInItsBatch) {
  // text_i = e_i, motion_i = -e_i: the matched distance is 2, every other sqrt(2).
  const int items = 64;
  const Embeddings text = Eigen::MatrixXd::Identity(items, items);
  const Embeddings motion = -text;
  RPrecisionOptions pairs;
  pairs.batch_size = 2;
  pairs.top_k = 2;
  const RPrecision second_nearest = r_precision(text, motion, pairs);
  EXPECT_EQ(second_nearest.top_k[0].mean, 0.0);
  EXPECT_EQ(second_nearest.top_k[1].mean, 1.0);
  EXPECT_NEAR(second_nearest.mm_dist.mean, 2.0, 1e-14) << "difference " << second_nearest.mm_dist.mean - 2.0;

  RPrecisionOptions fours;
  fours.batch_size = 4;
  const RPrecision farthest = r_precision(text, motion, fours);
  for (const Interval& r : farthest.top_k) EXPECT_EQ(r.mean, 0.0);
}

TEST(RPrecision, AllEqualEmbeddingsGiveChanceNotOne) {
  const Embeddings same = Eigen::MatrixXd::Ones(320, 8);
  const RPrecision result = r_precision(same, same);
  for (int k = 1; k <= 3; ++k) {
    EXPECT_NEAR(result.top_k[k - 1].mean, k / 32.0, 1e-12) << "R@" << k << " difference " << result.top_k[k - 1].mean - k / 32.0;
    EXPECT_NEAR(result.top_k[k - 1].half_width, 0.0, 1e-12);
  }
}

TEST(RPrecision, DropsTheIncompleteLastBatch) {
  const Embeddings points = random_embeddings(70, 4, 4);
  RPrecisionOptions options;
  options.repeats = 3;
  const RPrecision result = r_precision(points, points, options);
  EXPECT_EQ(result.batches_per_repeat, 2);  // 70 = 2 x 32 + 6 dropped
  EXPECT_EQ(result.top_k[0].mean, 1.0);
}

TEST(RPrecision, SameSeedRepeatsDifferentSeedDiffers) {
  const Embeddings text = random_embeddings(320, 8, 5), motion = random_embeddings(320, 8, 6);
  RPrecisionOptions options;
  const RPrecision first = r_precision(text, motion, options);
  const RPrecision again = r_precision(text, motion, options);
  options.seed = 1;
  const RPrecision other = r_precision(text, motion, options);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(first.top_k[k].mean, again.top_k[k].mean);
    EXPECT_EQ(first.top_k[k].half_width, again.top_k[k].half_width);
  }
  EXPECT_EQ(first.mm_dist.mean, again.mm_dist.mean);
  // Other batches, so other rankings (MM-Dist is a mean over all 320 items whichever the batches).
  EXPECT_NE(first.top_k[0].mean, other.top_k[0].mean);
  EXPECT_NE(first.top_k[2].mean, other.top_k[2].mean);
}

TEST(RPrecision, ChanceLevelIsKOverBatchSize) {
  EXPECT_EQ(r_precision_chance(1, 32), 1.0 / 32.0);
  EXPECT_EQ(r_precision_chance(3, 32), 3.0 / 32.0);
  EXPECT_EQ(r_precision_chance(4, 4), 1.0);
  EXPECT_THROW(r_precision_chance(0, 32), std::invalid_argument);
  EXPECT_THROW(r_precision_chance(33, 32), std::invalid_argument);
}

TEST(RPrecision, InvalidInputsThrow) {
  const Embeddings points = random_embeddings(64, 4, 7);
  EXPECT_THROW(r_precision(points, random_embeddings(63, 4, 8)), std::invalid_argument);
  EXPECT_THROW(r_precision(points, random_embeddings(64, 5, 8)), std::invalid_argument);
  EXPECT_THROW(r_precision(Embeddings(0, 4), Embeddings(0, 4)), std::invalid_argument);
  Embeddings with_nan = points;
  with_nan(3, 2) = std::nan("");
  EXPECT_THROW(r_precision(with_nan, points), std::invalid_argument);

  const Embeddings few = random_embeddings(20, 4, 9);
  const std::string message = message_of([&] { r_precision(few, few); });
  EXPECT_NE(message.find("20 items"), std::string::npos) << message;
  EXPECT_NE(message.find("32"), std::string::npos) << message;

  for (const auto& [field, change] : std::vector<std::pair<std::string, std::function<void(RPrecisionOptions&)>>>{
           {"batch_size", [](RPrecisionOptions& o) { o.batch_size = 1; }},
           {"repeats", [](RPrecisionOptions& o) { o.repeats = 0; }},
           {"top_k", [](RPrecisionOptions& o) { o.top_k = 0; }},
           {"top_k", [](RPrecisionOptions& o) { o.top_k = 33; }}}) {
    RPrecisionOptions options;
    change(options);
    const std::string error = message_of([&] { options.validate(); });
    EXPECT_NE(error.find(field), std::string::npos) << field << ": " << error;
  }
}

TEST(RPrecisionWithinGroups, BatchesStayInsideGroupsAndSmallGroupsAreSkipped) {
  // Groups "a" and "b" hold the same 64 points (text = motion), so a text of "a"
  // ties with its twin of "b" when both share a batch; "c" has 10 items, fewer than 32.
  const Embeddings shared = random_embeddings(64, 8, 10);
  const Embeddings small = random_embeddings(10, 8, 11);
  Embeddings points(138, 8);
  points << shared, shared, small;
  std::vector<std::string> groups(138, "c");
  std::fill(groups.begin(), groups.begin() + 64, "b");  // "b" first: groups are taken in name order anyway
  std::fill(groups.begin() + 64, groups.begin() + 128, "a");

  const RPrecision within = r_precision_within_groups(points, points, groups);
  EXPECT_EQ(within.batches_per_repeat, 4);
  EXPECT_EQ(within.skipped_groups, std::vector<std::string>{"c"});
  EXPECT_EQ(within.top_k[0].mean, 1.0);
  EXPECT_EQ(within.mm_dist.mean, 0.0);

  // Mixed batches: a twin in the batch (chance about 31 / 137) halves the hit, R@1 about 0.9.
  const RPrecision mixed = r_precision(points, points);
  EXPECT_LT(mixed.top_k[0].mean, 0.95);
}

TEST(RPrecisionWithinGroups, OneGroupIsThePlainRPrecision) {
  const Embeddings text = random_embeddings(100, 6, 12), motion = random_embeddings(100, 6, 13);
  const RPrecision plain = r_precision(text, motion);
  const RPrecision grouped = r_precision_within_groups(text, motion, std::vector<std::string>(100, "all"));
  for (int k = 0; k < 3; ++k) EXPECT_EQ(plain.top_k[k].mean, grouped.top_k[k].mean);
  EXPECT_EQ(plain.mm_dist.mean, grouped.mm_dist.mean);
  EXPECT_EQ(plain.batches_per_repeat, grouped.batches_per_repeat);
}

TEST(RPrecisionWithinGroups, NoBatchOrWrongLabelsThrow) {
  const Embeddings points = random_embeddings(60, 4, 14);
  std::vector<std::string> groups(60);
  for (int i = 0; i < 60; ++i) groups[i] = "group " + std::to_string(i % 3);  // three groups of 20
  const std::string message = message_of([&] { r_precision_within_groups(points, points, groups); });
  EXPECT_NE(message.find("60 items"), std::string::npos) << message;
  EXPECT_NE(message.find("32"), std::string::npos) << message;
  groups.pop_back();
  EXPECT_THROW(r_precision_within_groups(points, points, groups), std::invalid_argument);
}

// ---- FID ---------------------------------------------------------------------

TEST(SymmetricSqrt, SquaresBackToTheMatrix) {
  const Eigen::MatrixXd spd = random_spd(6, 20);
  const Eigen::MatrixXd root = symmetric_sqrt(spd);
  const double difference = max_difference(root * root, spd);
  EXPECT_LE(difference, 1e-12 * spd.cwiseAbs().maxCoeff()) << "max difference " << difference;
  EXPECT_LE(max_difference(root, root.transpose()), 1e-14);
}

TEST(SymmetricSqrt, RankOneMatrix) {
  // v vᵀ has the one eigenvalue |v|^2: its root is v vᵀ / |v|; the zero eigenvalues may round below 0.
  Eigen::VectorXd v(4);
  v << 1.0, -2.0, 0.5, 3.0;
  const Eigen::MatrixXd outer = v * v.transpose();
  const double difference = max_difference(symmetric_sqrt(outer), outer / v.norm());
  EXPECT_LE(difference, 1e-7) << "max difference " << difference;  // sqrt of a rounding-size eigenvalue is about 1e-8
}

TEST(FrechetDistance, OneDimensionalGaussians) {
  // (mu1 - mu2)^2 + (s1 - s2)^2 for standard deviations s.
  const double mu1 = 0.3, mu2 = -1.2, s1 = 0.5, s2 = 2.0;
  const double value = frechet_distance(Eigen::VectorXd::Constant(1, mu1), Eigen::MatrixXd::Constant(1, 1, s1 * s1),
                                        Eigen::VectorXd::Constant(1, mu2), Eigen::MatrixXd::Constant(1, 1, s2 * s2));
  const double expected = (mu1 - mu2) * (mu1 - mu2) + (s1 - s2) * (s1 - s2);
  EXPECT_NEAR(value, expected, 1e-12) << "difference " << value - expected;
}

// Diagonal covariances a, b and means: |mean1 - mean2|^2 + sum (sqrt(a_i) - sqrt(b_i))^2.
struct DiagonalCase {
  Eigen::VectorXd mean1, mean2, variances1, variances2;
  double expected() const {
    return (mean1 - mean2).squaredNorm() + (variances1.cwiseSqrt() - variances2.cwiseSqrt()).squaredNorm();
  }
};
DiagonalCase diagonal_case() {
  DiagonalCase c;
  c.mean1 = Eigen::VectorXd(5);
  c.mean1 << 0.0, 1.0, -2.0, 0.5, 3.0;
  c.mean2 = Eigen::VectorXd(5);
  c.mean2 << 1.0, 1.0, 0.0, -0.5, 2.0;
  c.variances1 = Eigen::VectorXd(5);
  c.variances1 << 1.0, 4.0, 0.25, 9.0, 2.0;
  c.variances2 = Eigen::VectorXd(5);
  c.variances2 << 4.0, 1.0, 0.25, 0.01, 3.0;
  return c;
}

TEST(FrechetDistance, DiagonalCovariances) {
  const DiagonalCase c = diagonal_case();
  const double value = frechet_distance(c.mean1, c.variances1.asDiagonal().toDenseMatrix(), c.mean2,
                                        c.variances2.asDiagonal().toDenseMatrix());
  EXPECT_NEAR(value, c.expected(), 1e-12) << "difference " << value - c.expected();
}

TEST(FrechetDistance, SameRotationOfBothGaussiansChangesNothing) {
  const DiagonalCase c = diagonal_case();
  const Eigen::MatrixXd rotation = random_rotation(5, 21);
  const Eigen::MatrixXd cov1 = rotation * c.variances1.asDiagonal() * rotation.transpose();
  const Eigen::MatrixXd cov2 = rotation * c.variances2.asDiagonal() * rotation.transpose();
  const double value = frechet_distance(rotation * c.mean1, (cov1 + cov1.transpose()) / 2.0, rotation * c.mean2,
                                        (cov2 + cov2.transpose()) / 2.0);
  EXPECT_NEAR(value, c.expected(), 1e-10) << "difference " << value - c.expected();
}

TEST(FrechetDistance, CommutingCovariances) {
  // cov2 = cov1^2 + cov1 shares cov1's eigenvectors: with its eigenvalues l the
  // trace term is sum (sqrt(l) - sqrt(l^2 + l))^2.
  const Eigen::MatrixXd cov1 = random_spd(4, 22);
  Eigen::MatrixXd cov2 = cov1 * cov1 + cov1;
  cov2 = (cov2 + cov2.transpose()) / 2.0;
  const Eigen::VectorXd l = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(cov1).eigenvalues();
  const double expected = (l.cwiseSqrt() - (l.cwiseProduct(l) + l).cwiseSqrt()).squaredNorm();
  const Eigen::VectorXd mean = Eigen::VectorXd::Zero(4);
  const double value = frechet_distance(mean, cov1, mean, cov2);
  EXPECT_NEAR(value, expected, 1e-10 * expected) << "difference " << value - expected;
}

TEST(FrechetDistance, InvalidInputsThrow) {
  const Eigen::VectorXd mean = Eigen::VectorXd::Zero(3);
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(3, 3);
  EXPECT_THROW(frechet_distance(mean, identity, Eigen::VectorXd::Zero(2), identity), std::invalid_argument);
  EXPECT_THROW(frechet_distance(mean, Eigen::MatrixXd::Identity(3, 2), mean, identity), std::invalid_argument);
  Eigen::MatrixXd asymmetric = identity;
  asymmetric(0, 1) = 0.5;
  EXPECT_THROW(frechet_distance(mean, identity, mean, asymmetric), std::invalid_argument);
  EXPECT_THROW(symmetric_sqrt(asymmetric), std::invalid_argument);
  EXPECT_THROW(symmetric_sqrt(Eigen::MatrixXd(2, 3)), std::invalid_argument);
}

TEST(FitGaussian, MeanAndUnbiasedCovariance) {
  Embeddings square(4, 2);
  square << 0, 0, 2, 0, 0, 2, 2, 2;
  const Gaussian gaussian = fit_gaussian(square);
  EXPECT_LE(max_difference(gaussian.mean, Eigen::Vector2d(1.0, 1.0)), 1e-15);
  // Each coordinate deviates by ±1: variance 4 / 3, covariance 0.
  const Eigen::MatrixXd expected = Eigen::Matrix2d::Identity() * (4.0 / 3.0);
  const double difference = max_difference(gaussian.covariance, expected);
  EXPECT_LE(difference, 1e-15) << "max difference " << difference;
  EXPECT_THROW(fit_gaussian(Embeddings(1, 2)), std::invalid_argument);
}

TEST(Fid, IdenticalSetsGiveZero) {
  const Embeddings a = random_embeddings(200, 8, 23);
  const double scale = fit_gaussian(a).covariance.trace();
  const double value = fid(a, a);
  EXPECT_NEAR(value, 0.0, 1e-9 * scale) << "difference " << value;
}

TEST(Fid, ShiftAddsTheSquaredShiftAndScalingHasAClosedForm) {
  const Embeddings a = random_embeddings(300, 6, 24);
  const Gaussian gaussian = fit_gaussian(a);
  Eigen::RowVectorXd shift(6);
  shift << 0.5, -1.0, 2.0, 0.0, 0.25, -0.75;
  const Embeddings shifted = a.rowwise() + shift;
  const double shifted_value = fid(a, shifted);
  EXPECT_NEAR(shifted_value, shift.squaredNorm(), 1e-9) << "difference " << shifted_value - shift.squaredNorm();

  // c a: mean c mu, covariance c^2 S, so (c S^2)^(1/2) = c S and FID = (1 - c)^2 (|mu|^2 + tr S).
  const double c = 1.7;
  const double expected = (1.0 - c) * (1.0 - c) * (gaussian.mean.squaredNorm() + gaussian.covariance.trace());
  const double scaled_value = fid(a, c * a);
  EXPECT_NEAR(scaled_value, expected, 1e-9) << "difference " << scaled_value - expected;
}

TEST(Fid, RankDeficientCovariancesStayFiniteAndNonNegative) {
  // 3 rows in 5 dimensions: covariances of rank 2.
  const Embeddings a = random_embeddings(3, 5, 25), b = random_embeddings(3, 5, 26);
  const double same = fid(a, a);
  EXPECT_NEAR(same, 0.0, 1e-6) << "difference " << same;  // the root of a rounding-size eigenvalue is about 1e-8
  const double different = fid(a, b);
  EXPECT_TRUE(std::isfinite(different));
  EXPECT_GT(different, 0.0);
}

TEST(Fid, InvalidInputsThrow) {
  const Embeddings a = random_embeddings(10, 4, 27);
  EXPECT_THROW(fid(a, random_embeddings(1, 4, 28)), std::invalid_argument);
  EXPECT_THROW(fid(a, random_embeddings(10, 3, 28)), std::invalid_argument);
  EXPECT_THROW(fid(Embeddings(0, 4), a), std::invalid_argument);
}

// ---- Diversity and Multimodality ---------------------------------------------------

// The fraction of pairs joining two different rows.
double distinct_fraction(const IndexPairs& pairs) {
  int distinct = 0;
  for (size_t i = 0; i < pairs.first.size(); ++i) distinct += pairs.first[i] != pairs.second[i];
  return static_cast<double>(distinct) / static_cast<double>(pairs.first.size());
}

TEST(DrawPairs, WithoutReplacementWhenThereAreEnoughRows) {
  const IndexPairs pairs = draw_pairs(40, 30, 7);
  ASSERT_EQ(pairs.first.size(), 30u);
  ASSERT_EQ(pairs.second.size(), 30u);
  for (const std::vector<int>* list : {&pairs.first, &pairs.second}) {
    EXPECT_EQ(std::set<int>(list->begin(), list->end()).size(), 30u);
    EXPECT_TRUE(std::all_of(list->begin(), list->end(), [](int i) { return i >= 0 && i < 40; }));
  }
  EXPECT_NE(pairs.first, pairs.second);
}

TEST(DrawPairs, WithReplacementWhenRowsAreFewerThanPairs) {
  const IndexPairs pairs = draw_pairs(8, 300, 7);
  ASSERT_EQ(pairs.first.size(), 300u);
  EXPECT_EQ(std::set<int>(pairs.first.begin(), pairs.first.end()).size(), 8u);  // every row, many times
  EXPECT_TRUE(std::all_of(pairs.second.begin(), pairs.second.end(), [](int i) { return i >= 0 && i < 8; }));
}

TEST(DrawPairs, SameSeedSameDrawsOtherSeedOthers) {
  EXPECT_EQ(draw_pairs(100, 50, 3).first, draw_pairs(100, 50, 3).first);
  EXPECT_EQ(draw_pairs(100, 50, 3).second, draw_pairs(100, 50, 3).second);
  EXPECT_NE(draw_pairs(100, 50, 3).first, draw_pairs(100, 50, 4).first);
  EXPECT_THROW(draw_pairs(0, 5, 0), std::invalid_argument);
  EXPECT_THROW(draw_pairs(5, 0, 0), std::invalid_argument);
}

TEST(Diversity, IdenticalRowsGiveZero) {
  EXPECT_EQ(diversity(Eigen::MatrixXd::Constant(50, 4, 0.3)), 0.0);
}

TEST(Diversity, SimplexGivesTheEdgeTimesTheDistinctFraction) {
  const double edge = 2.5;
  for (const auto& [rows, pairs] : std::vector<std::pair<int, int>>{{8, 300}, {40, 30}}) {
    DiversityOptions options;
    options.pairs = pairs;
    options.seed = 11;
    const double expected = edge * distinct_fraction(draw_pairs(rows, pairs, options.seed));
    const double value = diversity(simplex(rows, edge), options);
    EXPECT_NEAR(value, expected, 1e-12) << rows << " rows, difference " << value - expected;
    EXPECT_GT(value, 0.5 * edge);  // most pairs join different rows
  }
}

TEST(Diversity, InvalidInputsThrow) {
  EXPECT_THROW(diversity(random_embeddings(1, 4, 0)), std::invalid_argument);
  DiversityOptions options;
  options.pairs = 0;
  EXPECT_NE(message_of([&] { options.validate(); }).find("pairs"), std::string::npos);
}

TEST(Multimodality, IdenticalSamplesGiveZero) {
  const std::vector<Embeddings> captions{Eigen::MatrixXd::Constant(30, 4, 1.0), Eigen::MatrixXd::Constant(30, 4, -2.0)};
  EXPECT_EQ(multimodality(captions), 0.0);
}

TEST(Multimodality, SimplexPerCaptionReplaysEachCaptionsDraws) {
  // Caption c: samples on a simplex of edge d_c (padded to 30 columns), so its
  // mean pair distance is d_c times the fraction of its distinct pairs.
  const std::vector<std::pair<int, double>> shapes{{30, 1.0}, {12, 3.0}, {5, 0.5}};
  std::vector<Embeddings> captions;
  double expected = 0.0;
  MultimodalityOptions options;
  options.seed = 5;
  for (size_t c = 0; c < shapes.size(); ++c) {
    const auto [samples, edge] = shapes[c];
    Embeddings padded = Embeddings::Zero(samples, 30);
    padded.leftCols(samples) = simplex(samples, edge);
    captions.push_back(padded);
    const uint64_t caption_seed = mix64(options.seed ^ mix64(c));
    expected += edge * distinct_fraction(draw_pairs(samples, options.pairs, caption_seed)) / shapes.size();
  }
  const double value = multimodality(captions, options);
  EXPECT_NEAR(value, expected, 1e-12) << "difference " << value - expected;
}

TEST(Multimodality, InvalidInputsThrow) {
  EXPECT_THROW(multimodality({}), std::invalid_argument);
  EXPECT_THROW(multimodality({random_embeddings(30, 4, 0), random_embeddings(1, 4, 1)}), std::invalid_argument);
  EXPECT_THROW(multimodality({random_embeddings(30, 4, 0), random_embeddings(30, 5, 1)}), std::invalid_argument);
  MultimodalityOptions options;
  options.pairs = 0;
  EXPECT_NE(message_of([&] { options.validate(); }).find("pairs"), std::string::npos);
}

// ---- Coverage and Novelty --------------------------------------------------------

TEST(Windows, LengthIsTheMinimumAndStartsStepByStride) {
  EXPECT_EQ(window_length(120, 200, 90), 90);
  EXPECT_EQ(window_length(40, 200, 90), 40);
  EXPECT_EQ(window_length(120, 75, 90), 75);
  EXPECT_EQ(window_starts(10, 4, 1), (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));  // 10 - 4 + 1 windows
  EXPECT_EQ(window_starts(10, 4, 3), (std::vector<int>{0, 3, 6}));
  EXPECT_EQ(window_starts(10, 4, 4), (std::vector<int>{0, 4}));
  EXPECT_EQ(window_starts(4, 4, 1), (std::vector<int>{0}));
  EXPECT_THROW(window_starts(3, 4, 1), std::invalid_argument);
  EXPECT_THROW(window_starts(10, 4, 0), std::invalid_argument);
  EXPECT_THROW(window_length(0, 10, 90), std::invalid_argument);
}

TEST(CoverageNovelty, IdenticalSetsCoverFullyWithNoNovelty) {
  // Cosine 1 > θ for every θ < 1, not at θ = 1: trapezoid (99 + 0.5) / 100.
  const Embeddings windows = random_embeddings(40, 16, 30);
  const CoverageNovelty result = coverage_novelty(windows, windows);
  ASSERT_EQ(result.thresholds.size(), 101u);
  EXPECT_EQ(result.thresholds.front(), 0.0);
  EXPECT_EQ(result.thresholds.back(), 1.0);
  EXPECT_EQ(result.coverage[99], 1.0);
  EXPECT_EQ(result.coverage[100], 0.0);
  EXPECT_NEAR(result.coverage_auc, 0.995, 1e-12) << "difference " << result.coverage_auc - 0.995;
  EXPECT_EQ(result.novelty_auc, 0.0);
  EXPECT_TRUE(std::all_of(result.novelty.begin(), result.novelty.end(), [](double n) { return n == 0.0; }));
}

TEST(CoverageNovelty, OrthogonalSetsAreFullyNovel) {
  // Cosine 0 > 0 is false: no coverage; 1 - 0 > θ for θ < 1.
  const Eigen::MatrixXd axes = Eigen::MatrixXd::Identity(6, 6);
  const CoverageNovelty result = coverage_novelty(axes.topRows(3), 2.0 * axes.bottomRows(3));
  EXPECT_EQ(result.coverage_auc, 0.0);
  EXPECT_NEAR(result.novelty_auc, 0.995, 1e-12) << "difference " << result.novelty_auc - 0.995;
}

TEST(CoverageNovelty, KnownCosinesGiveKnownAreas) {
  // Reference e0, e2; generated g0 at cosine 0.555 to e0 and g1 at cosine 0.305
  // to e2, orthogonal otherwise. Between grid points, a step curve at c has area c.
  const double c0 = 0.555, c1 = 0.305;
  Embeddings reference = Embeddings::Zero(2, 4), generated = Embeddings::Zero(2, 4);
  reference(0, 0) = 1.0;
  reference(1, 2) = 1.0;
  generated.row(0) << c0, std::sqrt(1.0 - c0 * c0), 0.0, 0.0;
  generated.row(1) << 0.0, 0.0, c1, std::sqrt(1.0 - c1 * c1);
  generated *= 3.7;  // cosine ignores length

  const CoverageNovelty result = coverage_novelty(reference, generated);
  const double coverage = (c0 + c1) / 2.0, novelty = ((1.0 - c0) + (1.0 - c1)) / 2.0;
  EXPECT_NEAR(result.coverage_auc, coverage, 1e-12) << "difference " << result.coverage_auc - coverage;
  EXPECT_NEAR(result.novelty_auc, novelty, 1e-12) << "difference " << result.novelty_auc - novelty;
  EXPECT_EQ(result.coverage[30], 1.0);   // θ 0.30 < 0.305
  EXPECT_EQ(result.coverage[31], 0.5);   // only 0.555 > 0.31
  EXPECT_EQ(result.coverage[56], 0.0);
  EXPECT_EQ(result.novelty[44], 1.0);    // 0.445 and 0.695 > 0.44
  EXPECT_EQ(result.novelty[45], 0.5);
  EXPECT_EQ(result.novelty[70], 0.0);
}

TEST(CoverageNovelty, ZeroVectorHasCosineZero) {
  Embeddings reference = random_embeddings(2, 5, 31);
  reference.row(1).setZero();
  const CoverageNovelty result = coverage_novelty(reference, reference.topRows(1));
  EXPECT_EQ(result.coverage[0], 0.5);  // the zero window is not covered even at θ = 0
  EXPECT_EQ(result.novelty[0], 0.0);
}

TEST(CoverageNovelty, ThresholdCountSetsTheGrid) {
  const Embeddings windows = random_embeddings(10, 8, 32);
  CoverageNoveltyOptions options;
  options.thresholds = 11;
  const CoverageNovelty result = coverage_novelty(windows, windows, options);
  ASSERT_EQ(result.coverage.size(), 11u);
  EXPECT_NEAR(result.coverage_auc, 0.95, 1e-12) << "difference " << result.coverage_auc - 0.95;  // 1 - 0.5 / 10
}

TEST(CoverageNovelty, InvalidInputsThrow) {
  const Embeddings windows = random_embeddings(10, 8, 33);
  EXPECT_THROW(coverage_novelty(windows, random_embeddings(10, 7, 34)), std::invalid_argument);
  EXPECT_THROW(coverage_novelty(Embeddings(0, 8), windows), std::invalid_argument);
  CoverageNoveltyOptions options;
  options.thresholds = 1;
  EXPECT_NE(message_of([&] { options.validate(); }).find("thresholds"), std::string::npos);
}

// ---- Jitter --------------------------------------------------------------------

// (T, J, 3) positions with joint j at position(t, j) (a 3-vector) for t in seconds.
template <typename Path>
std::vector<double> trajectory(int frames, int joints, double fps, Path position) {
  std::vector<double> positions;
  for (int t = 0; t < frames; ++t) {
    for (int j = 0; j < joints; ++j) {
      const Eigen::Vector3d p = position(t / fps, j);
      positions.insert(positions.end(), {p.x(), p.y(), p.z()});
    }
  }
  return positions;
}

TEST(Jitter, LinearAndQuadraticPathsHaveNone) {
  const double fps = 30.0;
  const auto linear = trajectory(60, 3, fps, [](double t, int j) { return Eigen::Vector3d(1.0 + 2.0 * t, -t * j, 0.5); });
  const auto quadratic =
      trajectory(60, 3, fps, [](double t, int j) { return Eigen::Vector3d(t * t, 3.0 - 4.0 * t * t * j, 0.5 * t); });
  // Rounding of positions near 10, times fps^3 = 27000: about 1e-9.
  const double linear_value = jitter(linear, 60, 3, fps), quadratic_value = jitter(quadratic, 60, 3, fps);
  EXPECT_NEAR(linear_value, 0.0, 1e-7) << "difference " << linear_value;
  EXPECT_NEAR(quadratic_value, 0.0, 1e-7) << "difference " << quadratic_value;
}

TEST(Jitter, CubicPathHasJerkSixC) {
  // Joint j moves by c_j t^3 along a unit direction: jerk 6 |c_j| at every frame.
  const double fps = 30.0;
  const double c[] = {1.0, -0.5, 2.0};
  const Eigen::Vector3d directions[] = {Eigen::Vector3d::UnitX(), Eigen::Vector3d(0.6, 0.8, 0.0), Eigen::Vector3d::UnitZ()};
  // The explicit return type makes a vector, not an expression holding a dead temporary.
  const auto positions = trajectory(45, 3, fps, [&](double t, int j) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.1 * j, 0.0, 1.0) + c[j] * t * t * t * directions[j];
  });
  const double expected = 6.0 * (1.0 + 0.5 + 2.0) / 3.0;
  const double value = jitter(positions, 45, 3, fps);
  EXPECT_NEAR(value, expected, 1e-6) << "difference " << value - expected;
}

TEST(Jitter, AlternatingNoiseHasEightTimesItsAmplitude) {
  // x_t = a (-1)^t: third difference (-1)^t a (-1 - 3 - 3 - 1), norm 8 a, in units / s^3 times fps^3.
  const int frames = 10, joints = 2;
  const double amplitude = 0.25, fps = 20.0;
  std::vector<float> positions;
  for (int t = 0; t < frames; ++t) {
    for (int j = 0; j < joints; ++j) positions.insert(positions.end(), {0.0f, static_cast<float>(t % 2 ? -amplitude : amplitude), 1.0f});
  }
  const double expected = 8.0 * amplitude * fps * fps * fps;
  const double value = jitter(positions, frames, joints, fps);
  EXPECT_NEAR(value, expected, 1e-9 * expected) << "difference " << value - expected;
  const double as_double = jitter(std::vector<double>(positions.begin(), positions.end()), frames, joints, fps);
  EXPECT_EQ(as_double, value);
}

TEST(Jitter, InvalidInputsThrow) {
  EXPECT_THROW(jitter(std::vector<double>(3 * 3, 0.0), 3, 1, 30.0), std::invalid_argument);     // T < 4
  EXPECT_THROW(jitter(std::vector<double>(4 * 3 - 1, 0.0), 4, 1, 30.0), std::invalid_argument);  // wrong size
  EXPECT_THROW(jitter(std::vector<double>(4 * 3, 0.0), 4, 1, 0.0), std::invalid_argument);
  EXPECT_THROW(jitter(std::vector<double>(4 * 3, std::nan("")), 4, 1, 30.0), std::invalid_argument);
}

}  // namespace
}  // namespace nec::evaluator

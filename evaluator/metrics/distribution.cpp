// Metrics that compare two sets of embeddings (FID; Coverage and Novelty of
// Dragon appendix C) and the jitter of joint trajectories. See metrics.h.
#include "nec/evaluator/metrics.h"

#include "embedding_checks.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nec::evaluator {
namespace {

std::string shape_of(const Eigen::MatrixXd& matrix) {
  return std::to_string(matrix.rows()) + " x " + std::to_string(matrix.cols());
}

// Square, finite and symmetric up to rounding (relative 1e-9).
void require_symmetric(const Eigen::MatrixXd& matrix, const std::string& what) {
  if (matrix.rows() != matrix.cols() || matrix.rows() < 1) {
    throw std::invalid_argument(what + ": needs a non-empty square matrix, has " + shape_of(matrix));
  }
  if (!matrix.allFinite()) throw std::invalid_argument(what + ": has a non-finite value");
  const double scale = std::max(1.0, matrix.cwiseAbs().maxCoeff());
  if ((matrix - matrix.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    throw std::invalid_argument(what + ": the matrix is not symmetric");
  }
}

// A plain loop, not Eigen's vectorized dot, whose summation order may depend on
// alignment: equal rows then give bit-equal a·b, a·a and b·b, so a window's
// cosine with its own copy is exactly 1.
double dot(const double* a, const double* b, Eigen::Index size) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < size; ++i) sum += a[i] * b[i];
  return sum;
}

template <typename Scalar>
double jitter_of(const std::vector<Scalar>& positions, int frames, int joints, double fps) {
  if (frames < 4) throw std::invalid_argument("jitter: needs at least 4 frames for a third difference, has " + std::to_string(frames));
  if (joints < 1) throw std::invalid_argument("jitter: needs at least 1 joint, has " + std::to_string(joints));
  if (!(fps > 0.0) || !std::isfinite(fps)) throw std::invalid_argument("jitter: fps must be positive, is " + std::to_string(fps));
  const size_t expected = static_cast<size_t>(frames) * joints * 3;
  if (positions.size() != expected) {
    throw std::invalid_argument("jitter: positions has " + std::to_string(positions.size()) + " values, (T, J, 3) = (" +
                                std::to_string(frames) + ", " + std::to_string(joints) + ", 3) needs " +
                                std::to_string(expected));
  }
  for (Scalar value : positions) {
    if (!std::isfinite(value)) throw std::invalid_argument("jitter: positions has a non-finite value");
  }
  const auto at = [&](int frame, int joint, int axis) {
    return static_cast<double>(positions[(static_cast<size_t>(frame) * joints + joint) * 3 + axis]);
  };
  double sum = 0.0;
  for (int t = 0; t + 3 < frames; ++t) {
    for (int joint = 0; joint < joints; ++joint) {
      double squared = 0.0;
      for (int axis = 0; axis < 3; ++axis) {
        const double jerk = at(t + 3, joint, axis) - 3.0 * at(t + 2, joint, axis) + 3.0 * at(t + 1, joint, axis) -
                            at(t, joint, axis);
        squared += jerk * jerk;
      }
      sum += std::sqrt(squared);
    }
  }
  return sum / (static_cast<double>(frames - 3) * joints) * fps * fps * fps;
}

}  // namespace

Gaussian fit_gaussian(const Embeddings& embeddings) {
  require_embeddings(embeddings, "fit_gaussian", 2);
  Gaussian gaussian;
  gaussian.mean = embeddings.colwise().mean().transpose();
  const Eigen::MatrixXd centered = embeddings.rowwise() - gaussian.mean.transpose();
  const Eigen::MatrixXd covariance = centered.transpose() * centered / static_cast<double>(embeddings.rows() - 1);
  gaussian.covariance = (covariance + covariance.transpose()) / 2.0;  // the product is symmetric only up to rounding
  return gaussian;
}

Eigen::MatrixXd symmetric_sqrt(const Eigen::MatrixXd& matrix) {
  require_symmetric(matrix, "symmetric_sqrt");
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(matrix);
  const Eigen::VectorXd roots = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return solver.eigenvectors() * roots.asDiagonal() * solver.eigenvectors().transpose();
}

double frechet_distance(const Eigen::VectorXd& mean1, const Eigen::MatrixXd& cov1, const Eigen::VectorXd& mean2,
                        const Eigen::MatrixXd& cov2) {
  const Eigen::Index size = mean1.size();
  if (size < 1 || mean2.size() != size || cov1.rows() != size || cov1.cols() != size || cov2.rows() != size ||
      cov2.cols() != size) {
    throw std::invalid_argument("frechet_distance: needs means of one size D and (D, D) covariances, has means " +
                                std::to_string(mean1.size()) + " and " + std::to_string(mean2.size()) +
                                ", covariances " + shape_of(cov1) + " and " + shape_of(cov2));
  }
  if (!mean1.allFinite() || !mean2.allFinite()) throw std::invalid_argument("frechet_distance: a mean has a non-finite value");
  require_symmetric(cov1, "frechet_distance cov1");
  require_symmetric(cov2, "frechet_distance cov2");
  const Eigen::MatrixXd root1 = symmetric_sqrt(cov1);
  const Eigen::MatrixXd product = root1 * cov2 * root1;  // similar to cov1 cov2, so the same eigenvalues, but symmetric PSD
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver((product + product.transpose()) / 2.0,
                                                              Eigen::EigenvaluesOnly);
  const double trace_of_root = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt().sum();
  const double distance = (mean1 - mean2).squaredNorm() + cov1.trace() + cov2.trace() - 2.0 * trace_of_root;
  return std::max(distance, 0.0);  // equal Gaussians can round to a tiny negative value
}

double fid(const Embeddings& a, const Embeddings& b) {
  require_embeddings(a, "fid first set", 2);
  require_embeddings(b, "fid second set", 2);
  if (a.cols() != b.cols()) {
    throw std::invalid_argument("fid: the sets have " + std::to_string(a.cols()) + " and " + std::to_string(b.cols()) +
                                " columns; both need the same embedding dimension");
  }
  const Gaussian first = fit_gaussian(a);
  const Gaussian second = fit_gaussian(b);
  return frechet_distance(first.mean, first.covariance, second.mean, second.covariance);
}

int window_length(int reference_frames, int generated_frames, int max_window) {
  if (reference_frames < 1 || generated_frames < 1 || max_window < 1) {
    throw std::invalid_argument("window_length: needs positive frame counts and max_window, has " +
                                std::to_string(reference_frames) + ", " + std::to_string(generated_frames) + ", " +
                                std::to_string(max_window));
  }
  return std::min({reference_frames, generated_frames, max_window});
}

std::vector<int> window_starts(int frames, int window, int stride) {
  if (window < 1 || stride < 1 || window > frames) {
    throw std::invalid_argument("window_starts: needs 1 <= window <= frames and stride >= 1, has frames = " +
                                std::to_string(frames) + ", window = " + std::to_string(window) +
                                ", stride = " + std::to_string(stride));
  }
  std::vector<int> starts;
  for (int start = 0; start + window <= frames; start += stride) starts.push_back(start);
  return starts;
}

void CoverageNoveltyOptions::validate() const {
  if (thresholds < 2) {
    throw std::invalid_argument("CoverageNoveltyOptions: thresholds must be at least 2 (0 and 1), is " +
                                std::to_string(thresholds));
  }
}

CoverageNovelty coverage_novelty(const Embeddings& reference_windows, const Embeddings& generated_windows,
                                 const CoverageNoveltyOptions& options) {
  options.validate();
  require_embeddings(reference_windows, "coverage_novelty reference_windows", 1);
  require_embeddings(generated_windows, "coverage_novelty generated_windows", 1);
  if (reference_windows.cols() != generated_windows.cols()) {
    throw std::invalid_argument("coverage_novelty: reference windows have " + std::to_string(reference_windows.cols()) +
                                " columns, generated windows " + std::to_string(generated_windows.cols()));
  }
  // Transposed so that each window is one contiguous column.
  const Eigen::MatrixXd reference = reference_windows.transpose();
  const Eigen::MatrixXd generated = generated_windows.transpose();
  const Eigen::Index dimension = reference.rows();
  const auto squared_norms = [&](const Eigen::MatrixXd& windows) {
    std::vector<double> norms(windows.cols());
    for (Eigen::Index i = 0; i < windows.cols(); ++i) norms[i] = dot(windows.col(i).data(), windows.col(i).data(), dimension);
    return norms;
  };
  const std::vector<double> reference_norms = squared_norms(reference);
  const std::vector<double> generated_norms = squared_norms(generated);

  std::vector<double> best_for_reference(reference.cols(), -1.0);
  std::vector<double> best_for_generated(generated.cols(), -1.0);
  for (Eigen::Index r = 0; r < reference.cols(); ++r) {
    for (Eigen::Index g = 0; g < generated.cols(); ++g) {
      const double norms = reference_norms[r] * generated_norms[g];
      double cosine = 0.0;  // with a zero vector
      if (norms > 0.0) {
        // sqrt(x * x) == x in IEEE arithmetic, so a copy has cosine exactly 1; the clamp removes rounding past ±1.
        const double product = dot(reference.col(r).data(), generated.col(g).data(), dimension);
        cosine = std::clamp(product / std::sqrt(norms), -1.0, 1.0);
      }
      best_for_reference[r] = std::max(best_for_reference[r], cosine);
      best_for_generated[g] = std::max(best_for_generated[g], cosine);
    }
  }

  std::vector<double> distinctness(best_for_generated.size());  // 1 - best cosine, what novelty compares with θ
  std::transform(best_for_generated.begin(), best_for_generated.end(), distinctness.begin(), [](double c) { return 1.0 - c; });

  CoverageNovelty result;
  const double step = 1.0 / (options.thresholds - 1);
  for (int i = 0; i < options.thresholds; ++i) {
    const double theta = static_cast<double>(i) / (options.thresholds - 1);  // exactly 0 and 1 at the ends
    const auto fraction = [theta](const std::vector<double>& scores) {
      const auto above = std::count_if(scores.begin(), scores.end(), [theta](double s) { return s > theta; });
      return static_cast<double>(above) / static_cast<double>(scores.size());
    };
    result.thresholds.push_back(theta);
    result.coverage.push_back(fraction(best_for_reference));
    result.novelty.push_back(fraction(distinctness));
  }
  for (int i = 0; i + 1 < options.thresholds; ++i) {
    result.coverage_auc += (result.coverage[i] + result.coverage[i + 1]) / 2.0 * step;
    result.novelty_auc += (result.novelty[i] + result.novelty[i + 1]) / 2.0 * step;
  }
  return result;
}

double jitter(const std::vector<double>& positions, int frames, int joints, double fps) {
  return jitter_of(positions, frames, joints, fps);
}

double jitter(const std::vector<float>& positions, int frames, int joints, double fps) {
  return jitter_of(positions, frames, joints, fps);
}

}  // namespace nec::evaluator

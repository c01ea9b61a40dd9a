#include "fploc/plandiff/drawing_scale.h"

#include <algorithm>
#include <cmath>

namespace fploc::plandiff {

DrawingScale::DrawingScale(size_t elements)
    : eslot_(elements, -1), eg_(elements, 0.0), eh_(elements, 0.0), ep_(elements, 0.0), ec_(elements, 0.0),
      el_(elements, 0.0), en_(elements, 0), ef_(elements, 0) {}

void DrawingScale::add_point(int element, const Eigen::Vector3d& row, double offset) {
  sA_ += row * row.transpose();
  sg_ += row * offset;
  so2_ += offset * offset;
  ++scount_;
  int& slot = eslot_[size_t(element)];
  if (slot < 0) {
    slot = int(esums_.size());
    esums_.push_back({element, Eigen::Matrix3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0, 0});
  }
  ElementSums& es = esums_[size_t(slot)];
  es.A += row * row.transpose();
  es.g += row * offset;
  es.a += row;
  es.o += offset;
  ++es.n;
}

void DrawingScale::end_scan() {
  // The scan's bias (b) eliminated (Schur complement): what this scan tells about the scale.
  if (scount_ >= 20) {
    const Eigen::Matrix2d Abb = sA_.bottomRightCorner<2, 2>();
    const double det = Abb(0, 0) * Abb(1, 1) - Abb(0, 1) * Abb(1, 0);
    if (det > 1e-9 * std::max(1.0, Abb.trace() * Abb.trace())) {
      Eigen::Matrix2d inv;
      inv << Abb(1, 1), -Abb(0, 1), -Abb(1, 0), Abb(0, 0);
      inv /= det;
      const Eigen::Vector2d Asb = sA_.block<2, 1>(1, 0);
      h_ += sA_(0, 0) - Asb.dot(inv * Asb);
      g_ += sg_(0) - Asb.dot(inv * sg_.tail<2>());
      o2_ += so2_ - sg_.tail<2>().dot(inv * sg_.tail<2>());
      n_ += scount_ - 2;
      // Each element's part of the eliminated score, G_e - s H_e at any s: with w = (1, -Abb^-1 Asb) and the
      // scan's bias at s = 0, beta = Abb^-1 g_b, G_e = w.(g_e - A_e[:, b] beta), H_e = w.A_e w. Summed over
      // the elements they are the scan's g_ / h_ terms above.
      const Eigen::Vector2d k = inv * Asb, beta = inv * sg_.tail<2>();
      const Eigen::Vector3d w(1.0, -k.x(), -k.y());
      // An element's points' residuals at scale s with the scan's bias at s, beta - s k, summed: o_e - a_e.b beta
      // - s w.a_e. And an element standing delta off its line adds delta to each of its points' offsets, so
      // delta a_e to the scan's sums and delta w.a_e to its score (G = w.g).
      for (const ElementSums& es : esums_) {
        const size_t e = size_t(es.element);
        eg_[e] += w.dot(es.g - es.A.rightCols<2>() * beta);
        eh_[e] += w.dot(es.A * w);
        ep_[e] += es.o - es.a.tail<2>().dot(beta);
        ec_[e] += w.dot(es.a);
        en_[e] += es.n;
        el_[e] += es.a.tail<2>().dot(inv * es.a.tail<2>());
        ++ef_[e];
      }
    }
  }
  for (const ElementSums& es : esums_) eslot_[size_t(es.element)] = -1;
  esums_.clear();
  sA_.setZero();
  sg_.setZero();
  so2_ = 0;
  scount_ = 0;
}

DrawingScale::Estimate DrawingScale::estimate(int frames, int min_frames) const {
  Estimate d;
  if (!(h_ > 0 && n_ > 10)) return d;
  d.error = g_ / h_;
  const double var = std::max(0.0, (o2_ - d.error * g_) / (n_ - 1));
  // Points of one scan are not independent (the same walls, frame after frame): the sigma counts every
  // scan as one observation of its walls, i.e. it is inflated by sqrt(points per scan).
  const double per_scan = double(n_) / std::max(1, frames);
  d.sigma = std::sqrt(var / h_ * std::max(1.0, per_scan));
  // The walls themselves stand off their drawn lines (as built: a few cm each, for the whole run), and a
  // wall's offsets look like a scale to the scans that see it across a narrow room: every scan of that wall
  // repeats the same error. So the sigma is also taken with the walls as the independent units (the
  // sandwich variance clustered by element, with the small-sample factor C / (C - 1)); the larger is kept.
  double u2 = 0;
  int clusters = 0;
  for (size_t e = 0; e < eg_.size(); ++e) {
    if (!(eh_[e] > 0)) continue;
    const double u = eg_[e] - d.error * eh_[e];
    u2 += u * u;
    ++clusters;
  }
  if (clusters >= 2) d.sigma = std::max(d.sigma, std::sqrt(u2 * clusters / (clusters - 1)) / h_);
  // The walls stand off their drawn lines as built (a few cm each, for the whole run), and an offset reads as a
  // scale to every scan that sees its wall across a narrow corridor, the same error scan after scan: the walls
  // seen so far may happen to look like a consistent scale, which the scatter above cannot tell. So the sigma
  // also holds what offsets of the size the walls show can fake: an element delta_e off its line moves the
  // estimate by delta_e c_e / H (c_e: ec_), so independent offsets of sigma_w give sigma_w sqrt(sum_e c_e^2) / H.
  // sigma_w^2 is the sum over the elements seen in >= min_frames scans of their mean offset left by the scale and
  // the scans' biases, squared -- all walls, also those that carry no scale, so a few walls that fake one do not
  // hide the spread -- over the degrees of freedom those residuals keep: each element 1 less its mean leverage on
  // the scans' biases (across a corridor the bias takes about half of the two walls' offsets; without this the
  // sigma came out ~1.3x too small there).
  double m2 = 0, c2 = 0, dof = 0;
  int walls = 0;
  for (size_t e = 0; e < ec_.size(); ++e) {
    c2 += ec_[e] * ec_[e];
    if (ef_[e] < min_frames || en_[e] <= 0) continue;
    const double m = (ep_[e] - d.error * ec_[e]) / double(en_[e]);
    m2 += m * m;
    dof += std::max(0.0, 1.0 - el_[e] / double(en_[e]));
    ++walls;
  }
  if (walls >= 3 && dof > 0) d.sigma = std::hypot(d.sigma, std::sqrt(m2 / dof * c2) / h_);
  d.points = n_;
  return d;
}

}  // namespace fploc::plandiff

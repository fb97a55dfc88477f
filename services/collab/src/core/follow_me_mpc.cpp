// The follow-me MPC as an Ipopt TNLP; see follow_me_mpc.hpp for the formulation.
//
// Variables, N steps, m = 3 + n (base x, y, theta + n joints), K obstacle slots:
//   s_1..s_N (N m states), u_0..u_{N-1} (N m inputs), sigma (N K slacks, >= 0).
// Constraints: dynamics s_{k+1} - s_k - dt u_k = 0 (s_0 fixed: moved into the bounds), input
// differences u_k - u_{k-1} within +-a_max dt (u_{-1}: the command applied last cycle), and
// eq. 5 per step and slot. Duplicate sparse entries are summed by Ipopt, which keeps the
// obstacle terms' Hessian simple.
#include "collab/follow_me_mpc.hpp"

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include <Eigen/Dense>

#include <chrono>
#include <ctime>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace concert::collab {
namespace {

using Ipopt::Index;
using Ipopt::Number;
constexpr double kInf = 1e19;

// Writes a sparse matrix's structure (values == nullptr, Ipopt's first call) or its values, in
// the one fixed order of the caller's loops.
struct SparseOut {
  Index* row;
  Index* col;
  Number* v;
  std::size_t e{0};
  void operator()(std::size_t r, std::size_t c, double value) {
    if (v == nullptr) {
      row[e] = static_cast<Index>(r);
      col[e] = static_cast<Index>(c);
    } else {
      v[e] = value;
    }
    ++e;
  }
};

// CPU time of the calling thread [ms].
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

struct Problem : public Ipopt::TNLP {
  // Fixed by the constructor.
  std::size_t N{0}, n{0}, m{0}, K{0};
  double dt{0.1};
  MpcParams p;
  ArmLimits arm;

  // Set before each solve.
  Eigen::VectorXd s0;                 // m
  Eigen::VectorXd u_prev;             // m
  Eigen::Vector3d p0;                 // end-effector, world
  Eigen::MatrixXd P;                  // 3 x m: d p_ee / d s at s0
  std::vector<Eigen::Vector3d> ref;   // N: r_1..r_N
  std::vector<Eigen::Vector2d> obs;   // K: obstacle centres (x, y)
  std::vector<Eigen::Vector2d> off;   // K: the paired robot sphere's offset in the base frame
  // K: squared minimum distance. An unused slot keeps its constraint (Ipopt's warm start needs
  // the same structure every solve) with a far obstacle: inactive, multiplier ~0.
  std::vector<double> dmin2;
  Eigen::VectorXd w_u;                // m: input regularisation weights

  // Warm start (previous solution, shifted), and the solution.
  bool have_warm{false};
  Eigen::VectorXd x_warm, zl_warm, zu_warm, lam_warm;
  Eigen::VectorXd x_sol, zl_sol, zu_sol, lam_sol;
  Ipopt::SolverReturn status{Ipopt::UNASSIGNED};

  Index nvar() const { return static_cast<Index>(2 * N * m + N * K); }
  Index ncon() const { return static_cast<Index>(2 * N * m + N * K); }
  std::size_t is(std::size_t k) const { return (k - 1) * m; }      // s_k, k = 1..N
  std::size_t iu(std::size_t k) const { return N * m + k * m; }    // u_k, k = 0..N-1
  std::size_t isg(std::size_t k, std::size_t j) const { return 2 * N * m + k * K + j; }
  double base_acc_scale{1.0};         // set before each solve
  double acc_max(std::size_t i) const {
    if (i < 2) return base_acc_scale * p.base_lin_acc_max;
    if (i == 2) return base_acc_scale * p.base_ang_acc_max;
    return p.joint_acc_max;
  }

  bool get_nlp_info(Index& nv, Index& nc, Index& nnz_jac, Index& nnz_h, IndexStyleEnum& style) override {
    nv = nvar();
    nc = ncon();
    nnz_jac = static_cast<Index>(jac_count());
    nnz_h = static_cast<Index>(hess_count());
    style = C_STYLE;
    return true;
  }

  std::size_t jac_count() const { return (3 * N - 1) * m + (2 * N - 1) * m + N * K * 4; }
  std::size_t hess_count() const {
    return N * (m * (m + 1) / 2)  // state blocks
           + N * m                 // input diagonals
           + (N - 1) * m           // input differences, off-diagonal
           + N * K                 // slacks
           + N * K * 6;            // obstacle terms on (x, y, theta)
  }

  bool get_bounds_info(Index, Number* xl, Number* xu, Index, Number* gl, Number* gu) override {
    for (std::size_t k = 1; k <= N; ++k) {
      for (std::size_t i = 0; i < m; ++i) {
        const bool joint = i >= 3;
        xl[is(k) + i] = joint ? arm.q_min[static_cast<Index>(i - 3)] : -kInf;
        xu[is(k) + i] = joint ? arm.q_max[static_cast<Index>(i - 3)] : kInf;
      }
    }
    for (std::size_t k = 0; k < N; ++k) {
      for (std::size_t i = 0; i < m; ++i) {
        double v = 0;
        if (i < 2) v = p.base_lin_vel_max;
        else if (i == 2) v = p.base_ang_vel_max;
        else v = arm.qd_max[static_cast<Index>(i - 3)];
        xl[iu(k) + i] = -v;
        xu[iu(k) + i] = v;
      }
      for (std::size_t j = 0; j < K; ++j) {
        xl[isg(k, j)] = 0.0;
        xu[isg(k, j)] = kInf;
      }
    }
    std::size_t r = 0;
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t i = 0; i < m; ++i, ++r) gl[r] = gu[r] = (k == 0 ? s0[static_cast<Index>(i)] : 0.0);
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t i = 0; i < m; ++i, ++r) {
        const double a = acc_max(i) * dt;
        const double c = k == 0 ? u_prev[static_cast<Index>(i)] : 0.0;
        gl[r] = c - a;
        gu[r] = c + a;
      }
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t j = 0; j < K; ++j, ++r) {
        gl[r] = dmin2[j];
        gu[r] = kInf;
      }
    return true;
  }

  bool get_starting_point(Index nv, bool init_x, Number* x, bool init_z, Number* zl, Number* zu, Index nc,
                          bool init_lambda, Number* lam) override {
    if (init_x) {
      if (have_warm) {
        for (Index i = 0; i < nv; ++i) x[i] = x_warm[i];
      } else {
        for (std::size_t k = 1; k <= N; ++k)
          for (std::size_t i = 0; i < m; ++i) x[is(k) + i] = s0[static_cast<Index>(i)];
        for (std::size_t i = 2 * N * m - N * m; i < static_cast<std::size_t>(nv); ++i) x[i] = 0.0;
      }
    }
    if (init_z) {
      for (Index i = 0; i < nv; ++i) {
        zl[i] = have_warm ? zl_warm[i] : 1.0;
        zu[i] = have_warm ? zu_warm[i] : 1.0;
      }
    }
    if (init_lambda) {
      for (Index i = 0; i < nc; ++i) lam[i] = have_warm ? lam_warm[i] : 0.0;
    }
    return true;
  }

  // End-effector residual at step k (1..N).
  Eigen::Vector3d ee_residual(const Number* x, std::size_t k) const {
    Eigen::Map<const Eigen::VectorXd> s(x + is(k), static_cast<Index>(m));
    return p0 + P * (s - s0) - ref[k - 1];
  }

  bool eval_f(Index, const Number* x, bool, Number& f) override {
    f = 0;
    const auto nj = static_cast<Index>(n);
    for (std::size_t k = 1; k <= N; ++k) {
      f += p.w_ee * ee_residual(x, k).squaredNorm();
      Eigen::Map<const Eigen::VectorXd> q(x + is(k) + 3, nj);
      f += p.w_posture * (q - arm.q_posture).squaredNorm();
    }
    for (std::size_t k = 0; k < N; ++k) {
      Eigen::Map<const Eigen::VectorXd> u(x + iu(k), static_cast<Index>(m));
      f += (w_u.array() * u.array().square()).sum();
      const Eigen::VectorXd d = k == 0 ? Eigen::VectorXd(u - u_prev)
                                       : Eigen::VectorXd(u - Eigen::Map<const Eigen::VectorXd>(x + iu(k - 1), static_cast<Index>(m)));
      f += p.w_acc * d.squaredNorm();
      for (std::size_t j = 0; j < K; ++j) {
        const double sg = x[isg(k, j)];
        f += p.w_slack_lin * sg + p.w_slack_quad * sg * sg;
      }
    }
    return true;
  }

  bool eval_grad_f(Index nv, const Number* x, bool, Number* g) override {
    for (Index i = 0; i < nv; ++i) g[i] = 0;
    const auto nj = static_cast<Index>(n);
    const auto mm = static_cast<Index>(m);
    for (std::size_t k = 1; k <= N; ++k) {
      Eigen::Map<Eigen::VectorXd> gs(g + is(k), mm);
      gs += 2 * p.w_ee * P.transpose() * ee_residual(x, k);
      Eigen::Map<const Eigen::VectorXd> q(x + is(k) + 3, nj);
      gs.tail(nj) += 2 * p.w_posture * (q - arm.q_posture);
    }
    for (std::size_t k = 0; k < N; ++k) {
      Eigen::Map<const Eigen::VectorXd> u(x + iu(k), mm);
      Eigen::Map<Eigen::VectorXd> gu(g + iu(k), mm);
      gu += 2 * (w_u.array() * u.array()).matrix();
      if (k == 0) {
        gu += 2 * p.w_acc * (u - u_prev);
      } else {
        Eigen::Map<const Eigen::VectorXd> up(x + iu(k - 1), mm);
        gu += 2 * p.w_acc * (u - up);
        Eigen::Map<Eigen::VectorXd>(g + iu(k - 1), mm) -= 2 * p.w_acc * (u - up);
      }
      for (std::size_t j = 0; j < K; ++j) g[isg(k, j)] = p.w_slack_lin + 2 * p.w_slack_quad * x[isg(k, j)];
    }
    return true;
  }

  // Robot sphere centre, its theta derivative t and its rotated offset e, for slot j at state s.
  void sphere_terms(const Number* s, std::size_t j, Eigen::Vector2d& c, Eigen::Vector2d& t,
                    Eigen::Vector2d& e) const {
    const double ct = std::cos(s[2]);
    const double st = std::sin(s[2]);
    const Eigen::Vector2d& o = off[j];
    e = {ct * o.x() - st * o.y(), st * o.x() + ct * o.y()};
    t = {-e.y(), e.x()};
    c = Eigen::Vector2d(s[0], s[1]) + e;
  }

  bool eval_g(Index, const Number* x, bool, Index, Number* g) override {
    std::size_t r = 0;
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t i = 0; i < m; ++i, ++r) {
        const double prev = k == 0 ? 0.0 : x[is(k) + i];
        g[r] = x[is(k + 1) + i] - prev - dt * x[iu(k) + i];
      }
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t i = 0; i < m; ++i, ++r) g[r] = x[iu(k) + i] - (k == 0 ? 0.0 : x[iu(k - 1) + i]);
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t j = 0; j < K; ++j, ++r) {
        Eigen::Vector2d c, t, e;
        sphere_terms(x + is(k + 1), j, c, t, e);
        g[r] = (c - obs[j]).squaredNorm() + x[isg(k, j)];
      }
    return true;
  }

  bool eval_jac_g(Index, const Number* x, bool, Index, Index, Index* row, Index* col, Number* v) override {
    SparseOut put{row, col, v};
    std::size_t r = 0;
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t i = 0; i < m; ++i, ++r) {
        put(r, is(k + 1) + i, 1.0);
        if (k > 0) put(r, is(k) + i, -1.0);
        put(r, iu(k) + i, -dt);
      }
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t i = 0; i < m; ++i, ++r) {
        put(r, iu(k) + i, 1.0);
        if (k > 0) put(r, iu(k - 1) + i, -1.0);
      }
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t j = 0; j < K; ++j, ++r) {
        Eigen::Vector2d c, t, ev, d;
        if (x != nullptr) {
          sphere_terms(x + is(k + 1), j, c, t, ev);
          d = c - obs[j];
        } else {
          d.setZero();
          t.setZero();
        }
        put(r, is(k + 1) + 0, 2 * d.x());
        put(r, is(k + 1) + 1, 2 * d.y());
        put(r, is(k + 1) + 2, 2 * d.dot(t));
        put(r, isg(k, j), 1.0);
      }
    return true;
  }

  bool eval_h(Index, const Number* x, bool, Number of, Index, const Number* lam, bool, Index, Index* row,
              Index* col, Number* v) override {
    SparseOut put{row, col, v};
    const Eigen::MatrixXd PtP = 2 * p.w_ee * P.transpose() * P;
    for (std::size_t k = 1; k <= N; ++k)
      for (std::size_t a = 0; a < m; ++a)
        for (std::size_t b = 0; b <= a; ++b) {
          double h = PtP(static_cast<Index>(a), static_cast<Index>(b));
          if (a == b && a >= 3) h += 2 * p.w_posture;
          put(is(k) + a, is(k) + b, of * h);
        }
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t i = 0; i < m; ++i) {
        const double acc = (k + 1 < N) ? 4 * p.w_acc : 2 * p.w_acc;
        put(iu(k) + i, iu(k) + i, of * (2 * w_u[static_cast<Index>(i)] + acc));
      }
    for (std::size_t k = 1; k < N; ++k)
      for (std::size_t i = 0; i < m; ++i) put(iu(k) + i, iu(k - 1) + i, of * (-2 * p.w_acc));
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t j = 0; j < K; ++j) put(isg(k, j), isg(k, j), of * 2 * p.w_slack_quad);
    const std::size_t r0 = 2 * N * m;
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t j = 0; j < K; ++j) {
        double l = 0;
        Eigen::Vector2d c, t, ev, d;
        if (v != nullptr) {
          l = lam[r0 + k * K + j];
          sphere_terms(x + is(k + 1), j, c, t, ev);
          d = c - obs[j];
        } else {
          t.setZero();
          ev.setZero();
          d.setZero();
        }
        const std::size_t b = is(k + 1);
        put(b + 0, b + 0, 2 * l);
        put(b + 1, b + 1, 2 * l);
        put(b + 2, b + 0, 2 * l * t.x());
        put(b + 2, b + 1, 2 * l * t.y());
        put(b + 2, b + 2, 2 * l * (t.squaredNorm() - d.dot(ev)));
        put(b + 1, b + 0, 0.0);
      }
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn st, Index nv, const Number* x, const Number* zl, const Number* zu,
                         Index nc, const Number*, const Number* lam, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    status = st;
    x_sol = Eigen::Map<const Eigen::VectorXd>(x, nv);
    zl_sol = Eigen::Map<const Eigen::VectorXd>(zl, nv);
    zu_sol = Eigen::Map<const Eigen::VectorXd>(zu, nv);
    lam_sol = Eigen::Map<const Eigen::VectorXd>(lam, nc);
  }

  // Slot j's warm start as an inactive constraint's: no slack, no multiplier, the slack's bound
  // multiplier at the slack's marginal cost.
  void reset_slot(std::size_t j) {
    for (std::size_t k = 0; k < N; ++k) {
      x_warm[static_cast<Index>(isg(k, j))] = 0.0;
      zl_warm[static_cast<Index>(isg(k, j))] = p.w_slack_lin;
      zu_warm[static_cast<Index>(isg(k, j))] = 0.0;
      lam_warm[static_cast<Index>(2 * N * m + k * K + j)] = 0.0;
    }
  }

  // The previous solution moved one step earlier (the last step repeated): the next warm start.
  void shift_solution(bool shift) {
    auto shift_blocks = [](Eigen::VectorXd& v, std::size_t start, std::size_t blocks, std::size_t size) {
      for (std::size_t k = 0; k + 1 < blocks; ++k)
        v.segment(static_cast<Index>(start + k * size), static_cast<Index>(size)) =
            v.segment(static_cast<Index>(start + (k + 1) * size), static_cast<Index>(size));
    };
    x_warm = x_sol;
    zl_warm = zl_sol;
    zu_warm = zu_sol;
    lam_warm = lam_sol;
    if (!shift) {
      have_warm = true;  // less than a step later: the solution itself is the better guess
      return;
    }
    for (Eigen::VectorXd* v : {&x_warm, &zl_warm, &zu_warm}) {
      shift_blocks(*v, 0, N, m);
      shift_blocks(*v, N * m, N, m);
      shift_blocks(*v, 2 * N * m, N, K);
    }
    shift_blocks(lam_warm, 0, N, m);
    shift_blocks(lam_warm, N * m, N, m);
    shift_blocks(lam_warm, 2 * N * m, N, K);
    have_warm = true;
  }
};

}  // namespace

struct FollowMeMpc::Impl {
  Ipopt::SmartPtr<Problem> problem;
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app;
  bool solved_once{false};
  bool warm_options{false};
  Eigen::Vector3d virtual_velocity{Eigen::Vector3d::Zero()};
  double since_shift{0.0};  // time since the warm start last moved a step [s]
  Eigen::Vector3d force{Eigen::Vector3d::Zero()};  // the low-passed force (params.force_filter)
  bool force_valid{false};
  // The obstacle in each constraint slot at the last solve (slot_used false: inert), so that an
  // obstacle keeps its slot from one solve to the next and the warm start's slack and multipliers
  // stay its own (the grid hands them over sorted by distance: the order changes as the base moves).
  std::vector<bool> slot_used;
  std::vector<Eigen::Vector2d> slot_centre;
};

FollowMeMpc::FollowMeMpc(MpcParams params, ArmLimits arm, std::vector<RobotSphere> robot_spheres)
    : params_(params), arm_(std::move(arm)), spheres_(std::move(robot_spheres)), impl_(std::make_unique<Impl>()) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("follow-me MPC: " + what); };
  if (params_.horizon < 2 || params_.horizon > 200) bad("horizon must be 2..200 steps");
  if (!(params_.dt > 0.0)) bad("dt must be > 0");
  if ((params_.mass.array() <= 0.0).any() || (params_.damping.array() < 0.0).any())
    bad("virtual mass must be > 0 and damping >= 0 on every axis");
  const auto nj = arm_.q_min.size();
  if (nj < 1) bad("the arm has no joints");
  if (arm_.q_max.size() != nj || arm_.qd_max.size() != nj || arm_.q_posture.size() != nj)
    bad("q_min, q_max, qd_max and q_posture must have one entry per joint (" + std::to_string(nj) + ")");
  for (Eigen::Index i = 0; i < nj; ++i) {
    if (!(arm_.q_min[i] < arm_.q_max[i])) bad("joint " + std::to_string(i) + ": q_min must be < q_max");
    if (!(arm_.qd_max[i] > 0)) bad("joint " + std::to_string(i) + ": qd_max must be > 0");
  }
  if (spheres_.empty()) bad("no robot spheres");
  if (params_.max_obstacles > 64) bad("max_obstacles must be <= 64");
  if (!(params_.force_filter >= 0.0)) bad("force_filter must be >= 0 s");
  if (!(params_.slot_match >= 0.0)) bad("slot_match must be >= 0 m");
  if (!(params_.min_base_acceleration_scale > 0.0 && params_.min_base_acceleration_scale <= 1.0))
    bad("min_base_acceleration_scale must be in (0, 1]");

  auto& pb = impl_->problem;
  pb = new Problem();
  pb->N = params_.horizon;
  pb->n = static_cast<std::size_t>(nj);
  pb->m = 3 + pb->n;
  pb->K = params_.max_obstacles;
  pb->dt = params_.dt;
  pb->p = params_;
  pb->arm = arm_;
  pb->ref.assign(pb->N, Eigen::Vector3d::Zero());
  pb->obs.assign(pb->K, Eigen::Vector2d::Zero());
  pb->off.assign(pb->K, Eigen::Vector2d::Zero());
  pb->dmin2.assign(pb->K, 0.0);
  pb->u_prev = Eigen::VectorXd::Zero(static_cast<Index>(pb->m));
  pb->w_u = Eigen::VectorXd::Constant(static_cast<Index>(pb->m), params_.w_joint_vel);
  pb->w_u.head(3).setConstant(params_.w_base_vel);
  impl_->slot_used.assign(pb->K, false);
  impl_->slot_centre.assign(pb->K, Eigen::Vector2d::Zero());

  auto& app = impl_->app;
  app = IpoptApplicationFactory();
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");
  app->Options()->SetIntegerValue("max_iter", params_.max_iter);
  app->Options()->SetNumericValue("tol", 1e-5);
  app->Options()->SetNumericValue("acceptable_tol", 1e-2);
  app->Options()->SetIntegerValue("acceptable_iter", 2);
  app->Options()->SetStringValue("linear_solver", "mumps");
  // No MC64 permutation/scaling in MUMPS: the KKT matrices here are small and well scaled, and
  // MUMPS recomputes the scaling at every solve. Measured with bench_collab_mpc, CPU time of the
  // solving thread (the wall time on this loaded machine is mostly waiting): median 6.6 -> 4.6 ms,
  // the same iterations and closed-loop figures.
  app->Options()->SetIntegerValue("mumps_permuting_scaling", 0);
  app->Options()->SetIntegerValue("mumps_scaling", 0);
  // COLLAB_MPC_DERIVATIVE_TEST=first-order|second-order: Ipopt's derivative checker (README).
  if (const char* dt = std::getenv("COLLAB_MPC_DERIVATIVE_TEST")) {
    app->Options()->SetStringValue("derivative_test", dt);
    app->Options()->SetIntegerValue("print_level", 4);
    app->Options()->SetNumericValue("point_perturbation_radius", 0.0);
  }
  // COLLAB_MPC_IPOPT="name=value;name=value": extra Ipopt options, for tuning (README).
  if (const char* extra = std::getenv("COLLAB_MPC_IPOPT")) {
    std::string all(extra);
    std::size_t at = 0;
    while (at < all.size()) {
      const std::size_t end = std::min(all.find(';', at), all.size());
      const std::string item = all.substr(at, end - at);
      at = end + 1;
      const std::size_t eq = item.find('=');
      if (eq == std::string::npos) bad("COLLAB_MPC_IPOPT: '" + item + "' is not name=value");
      const std::string name = item.substr(0, eq), value = item.substr(eq + 1);
      char* stop = nullptr;
      const long iv = std::strtol(value.c_str(), &stop, 10);
      bool ok = false;
      if (stop != nullptr && *stop == '\0' && !value.empty()) ok = app->Options()->SetIntegerValue(name, static_cast<Index>(iv));
      if (!ok) {
        const double dv = std::strtod(value.c_str(), &stop);
        if (stop != nullptr && *stop == '\0' && !value.empty()) ok = app->Options()->SetNumericValue(name, dv);
      }
      if (!ok) ok = app->Options()->SetStringValue(name, value);
      if (!ok) bad("COLLAB_MPC_IPOPT: Ipopt refused " + item);
    }
  }
  if (app->Initialize() != Ipopt::Solve_Succeeded) bad("Ipopt failed to initialise");
}

FollowMeMpc::~FollowMeMpc() = default;

void FollowMeMpc::reset() {
  impl_->problem->have_warm = false;
  impl_->problem->u_prev.setZero();
  impl_->virtual_velocity.setZero();
  impl_->since_shift = 0.0;
  impl_->force_valid = false;
  impl_->slot_used.assign(impl_->slot_used.size(), false);
}

void FollowMeMpc::set_posture(const Eigen::VectorXd& q) {
  if (q.size() != arm_.q_min.size())
    throw std::invalid_argument("FollowMeMpc::set_posture: " + std::to_string(q.size()) + " values for " +
                                std::to_string(arm_.q_min.size()) + " joints");
  for (Eigen::Index i = 0; i < q.size(); ++i)
    if (!(q[i] >= arm_.q_min[i] && q[i] <= arm_.q_max[i]))
      throw std::invalid_argument("FollowMeMpc::set_posture: joint " + std::to_string(i) + " at " +
                                  std::to_string(q[i]) + " is outside its limits");
  arm_.q_posture = q;
  impl_->problem->arm.q_posture = q;
}

MpcResult FollowMeMpc::solve(const MpcInput& in) {
  MpcResult out;
  auto& pb = *impl_->problem;
  const auto nj = static_cast<Index>(pb.n);
  out.joint_velocity = Eigen::VectorXd::Zero(nj);
  if (in.q.size() != nj || in.arm_jacobian.rows() != 3 || in.arm_jacobian.cols() != nj) {
    out.status = "input sizes: q has " + std::to_string(in.q.size()) + " entries and the arm Jacobian is " +
                 std::to_string(in.arm_jacobian.rows()) + "x" + std::to_string(in.arm_jacobian.cols()) +
                 ", expected " + std::to_string(nj) + " and 3x" + std::to_string(nj);
    return out;
  }
  if (!in.base.allFinite() || !in.q.allFinite() || !in.ee_in_base.allFinite() || !in.arm_jacobian.allFinite() ||
      !in.force.allFinite()) {
    out.status = "input has a NaN or infinite value";
    return out;
  }
  if (!std::isfinite(in.period) || in.period < 0.0) {
    out.status = "period must be >= 0 (0: one step), got " + std::to_string(in.period);
    return out;
  }
  if (!(in.base_acceleration_scale >= 0.0 && in.base_acceleration_scale <= 1.0)) {
    out.status = "base acceleration scale must be in [0, 1], got " + std::to_string(in.base_acceleration_scale);
    return out;
  }
  pb.base_acc_scale = std::max(params_.min_base_acceleration_scale, in.base_acceleration_scale);
  const double period = in.period > 0.0 ? in.period : params_.dt;
  if (in.obstacles.size() > pb.K) {
    out.status = std::to_string(in.obstacles.size()) + " obstacles, at most " + std::to_string(pb.K);
    return out;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = thread_cpu_ms();
  // State and end-effector linearisation.
  pb.s0.resize(static_cast<Index>(pb.m));
  pb.s0.head(3) = in.base;
  pb.s0.tail(nj) = in.q;
  const double ct = std::cos(in.base.z());
  const double st = std::sin(in.base.z());
  Eigen::Matrix3d R;
  R << ct, -st, 0, st, ct, 0, 0, 0, 1;
  pb.p0 = Eigen::Vector3d(in.base.x(), in.base.y(), 0.0) + R * in.ee_in_base;
  pb.P = Eigen::MatrixXd::Zero(3, static_cast<Index>(pb.m));
  pb.P(0, 0) = 1;
  pb.P(1, 1) = 1;
  pb.P(0, 2) = -st * in.ee_in_base.x() - ct * in.ee_in_base.y();
  pb.P(1, 2) = ct * in.ee_in_base.x() - st * in.ee_in_base.y();
  pb.P.rightCols(nj) = R * in.arm_jacobian;
  // The force, low-passed (params.force_filter): the robot's estimate is quasi-static and reads
  // the arm's and base's accelerations as force, in spikes the reference would follow.
  if (!impl_->force_valid || params_.force_filter <= 0.0) {
    impl_->force = in.force;
    impl_->force_valid = true;
  } else {
    impl_->force += period / (params_.force_filter + period) * (in.force - impl_->force);
  }
  const Eigen::Vector3d force = impl_->force;
  out.force = force;
  // Eq. 4 integrated over the horizon from the end-effector's position (semi-implicit Euler).
  Eigen::Vector3d xv = pb.p0;
  Eigen::Vector3d vv = impl_->virtual_velocity;
  for (std::size_t k = 0; k < pb.N; ++k) {
    const Eigen::Vector3d acc = (force - params_.damping.cwiseProduct(vv)).cwiseQuotient(params_.mass);
    vv += params_.dt * acc;
    xv += params_.dt * vv;
    pb.ref[k] = xv;
    if (k == 0) {
      // The mass-damper's state after one control period (the first of the steps above when
      // the period is a step), kept for the next solve.
      const Eigen::Vector3d v0 = impl_->virtual_velocity;
      out.virtual_velocity = v0 + period * (force - params_.damping.cwiseProduct(v0)).cwiseQuotient(params_.mass);
    }
  }
  // Eq. 5: each obstacle in a slot (the one it had last solve when it is within slot_match of
  // where it was: the grid's nearest cell moves a cell at a time), paired with the robot sphere
  // nearest to it now. A slot that changes hands starts from an inactive constraint's warm start.
  std::vector<int> slot_of(in.obstacles.size(), -1);
  if (params_.slot_match <= 0.0) {
    // The input's order (the grid's: by distance), the warm start kept as it is.
    for (std::size_t i = 0; i < in.obstacles.size(); ++i) slot_of[i] = static_cast<int>(i);
  } else {
    std::vector<std::pair<double, std::pair<std::size_t, std::size_t>>> pairs;
    for (std::size_t i = 0; i < in.obstacles.size(); ++i)
      for (std::size_t j = 0; j < pb.K; ++j)
        if (impl_->slot_used[j]) {
          const double d = (in.obstacles[i].centre.head<2>() - impl_->slot_centre[j]).norm();
          if (d <= params_.slot_match) pairs.push_back({d, {i, j}});
        }
    std::sort(pairs.begin(), pairs.end());
    std::vector<bool> taken(pb.K, false);
    for (const auto& [d, ij] : pairs)
      if (slot_of[ij.first] < 0 && !taken[ij.second]) {
        slot_of[ij.first] = static_cast<int>(ij.second);
        taken[ij.second] = true;
      }
    std::vector<bool> fresh(pb.K, false);
    for (std::size_t i = 0; i < in.obstacles.size(); ++i) {
      if (slot_of[i] >= 0) continue;
      // A free slot, one that was inert last solve if there is one.
      std::size_t j = pb.K;
      for (std::size_t c = 0; c < pb.K && j == pb.K; ++c)
        if (!taken[c] && !impl_->slot_used[c]) j = c;
      for (std::size_t c = 0; c < pb.K && j == pb.K; ++c)
        if (!taken[c]) j = c;
      slot_of[i] = static_cast<int>(j);
      taken[j] = true;
      fresh[j] = true;
    }
    for (std::size_t j = 0; j < pb.K; ++j) {
      if (impl_->slot_used[j] && !taken[j]) fresh[j] = true;  // its obstacle went: inert now
      impl_->slot_used[j] = taken[j];
    }
    for (std::size_t i = 0; i < in.obstacles.size(); ++i)
      impl_->slot_centre[static_cast<std::size_t>(slot_of[i])] = in.obstacles[i].centre.head<2>();
    if (pb.have_warm)
      for (std::size_t j = 0; j < pb.K; ++j)
        if (fresh[j]) pb.reset_slot(j);
  }
  std::vector<int> obstacle_in(pb.K, -1);
  for (std::size_t i = 0; i < in.obstacles.size(); ++i) obstacle_in[static_cast<std::size_t>(slot_of[i])] = static_cast<int>(i);
  for (std::size_t j = 0; j < pb.K; ++j) {
    if (obstacle_in[j] < 0) {
      pb.dmin2[j] = 0.01;
      pb.obs[j] = pb.s0.head(2) + Eigen::Vector2d(50.0, 0.0);
      pb.off[j].setZero();
      continue;
    }
    const auto& o = in.obstacles[static_cast<std::size_t>(obstacle_in[j])];
    const Eigen::Vector2d oc = o.centre.head(2);
    double best = kInf;
    for (const auto& sph : spheres_) {
      const Eigen::Vector2d c = pb.s0.head(2) + R.topLeftCorner(2, 2) * sph.offset;
      const double d = (c - oc).norm() - sph.radius;
      if (d < best) {
        best = d;
        pb.off[j] = sph.offset;
        const double dm = sph.radius + o.radius + params_.margin;
        pb.dmin2[j] = dm * dm;
      }
    }
    pb.obs[j] = oc;
  }
  Ipopt::ApplicationReturnStatus st_app;
  auto opts = impl_->app->Options();
  if (!impl_->solved_once || !pb.have_warm) {
    if (impl_->warm_options) {
      impl_->warm_options = false;
      opts->SetStringValue("warm_start_init_point", "no");
      opts->SetNumericValue("mu_init", 0.1);
    }
    st_app = impl_->app->OptimizeTNLP(impl_->problem);
  } else {
    if (!impl_->warm_options) {
      impl_->warm_options = true;
      opts->SetStringValue("warm_start_init_point", "yes");
      opts->SetNumericValue("warm_start_bound_push", 1e-6);
      opts->SetNumericValue("warm_start_bound_frac", 1e-6);
      opts->SetNumericValue("warm_start_slack_bound_push", 1e-6);
      opts->SetNumericValue("warm_start_slack_bound_frac", 1e-6);
      opts->SetNumericValue("warm_start_mult_bound_push", 1e-6);
      opts->SetNumericValue("mu_init", 1e-4);
    }
    out.warm = true;
    st_app = impl_->app->ReOptimizeTNLP(impl_->problem);
  }
  impl_->solved_once = true;
  const auto stats = impl_->app->Statistics();
  if (Ipopt::IsValid(stats)) out.iterations = stats->IterationCount();
  out.solve_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  out.solve_cpu_ms = thread_cpu_ms() - cpu0;
  bool good = st_app == Ipopt::Solve_Succeeded || st_app == Ipopt::Solved_To_Acceptable_Level;
  // At the iteration limit (a pull straight at an obstacle: left or right?), the last iterate is
  // used when it is feasible (dynamics, bounds, eq. 5 with its slack): a real-time iteration.
  bool feasible_iterate = false;
  if (st_app == Ipopt::Maximum_Iterations_Exceeded && Ipopt::IsValid(stats)) {
    Number dual = 0, viol = 0, compl_ = 0, kkt = 0;
    stats->Infeasibilities(dual, viol, compl_, kkt);
    feasible_iterate = viol <= 1e-6;
    good = feasible_iterate;
  }
  if (!good || pb.x_sol.size() != pb.nvar()) {
    out.status = "Ipopt status " + std::to_string(static_cast<int>(st_app));
    pb.have_warm = false;  // the next solve starts cold
    pb.u_prev.setZero();
    return out;
  }
  out.ok = true;
  out.status = st_app == Ipopt::Solve_Succeeded ? "solved"
               : feasible_iterate                ? "iteration limit: feasible iterate used"
                                                 : "solved to acceptable level";
  const Eigen::VectorXd u0 = pb.x_sol.segment(static_cast<Index>(pb.iu(0)), static_cast<Index>(pb.m));
  out.base_velocity = u0.head(3);
  out.base_velocity_local = Eigen::Vector3d(ct * u0.x() + st * u0.y(), -st * u0.x() + ct * u0.y(), u0.z());
  out.joint_velocity = u0.tail(nj);
  out.max_slack = pb.x_sol.tail(static_cast<Index>(pb.N * pb.K)).maxCoeff();
  pb.u_prev = u0;
  impl_->since_shift += period;
  const bool shift = impl_->since_shift >= params_.dt - 1e-9;
  if (shift) impl_->since_shift = 0.0;
  pb.shift_solution(shift);
  impl_->virtual_velocity = out.virtual_velocity;
  return out;
}

Eigen::Vector3d planar_world_force(const Eigen::Vector3d& force_in_base, double base_yaw) {
  const Eigen::Vector2d f = Eigen::Rotation2Dd(base_yaw) * force_in_base.head<2>();
  return {f.x(), f.y(), 0.0};
}

void integrate_position_command(Eigen::VectorXd& q_cmd, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                double dt, double wind_up, const ArmLimits& limits) {
  if (q_cmd.size() != q.size()) q_cmd = q;
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    q_cmd[i] = std::clamp(q_cmd[i] + qd[i] * dt, q[i] - wind_up, q[i] + wind_up);
    q_cmd[i] = std::clamp(q_cmd[i], limits.q_min[i], limits.q_max[i]);
  }
}

}  // namespace concert::collab

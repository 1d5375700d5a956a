// The fast mode's two reductions against the direct per-match sums they replace:
// knot-interpolated poses of moving scans (pose_knots.h) and the quadratic form of rigid pairs
// (rigid_pair.h), both inside MatchProblem.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "core/calib/pair_matching.h"
#include "core/calib/point_to_plane.h"
#include "core/calib/projection.h"
#include "core/model/jacobian.h"
#include "tests/calib/synthetic.h"

namespace selfcal::calib {
namespace {

// Two sweeps of a LiDAR turning A7 (and a little A1), as the hokuyo scenarios do at 20 deg/s.
std::vector<Dataset> TwoSweeps(const RobotModel& truth, double seconds) {
  const testing::Scene scene = testing::RoomScene();
  testing::LidarSweepOptions options;
  options.seconds = seconds;
  const std::vector<double> a0 = {0.3, 0.7, 0.1, -1.3, 0.2, 0.8, -1.2};
  std::vector<double> a1 = a0;
  a1[6] += 0.35 * seconds;
  a1[0] += 0.05 * seconds;
  const std::vector<double> b0 = {0.5, 0.6, -0.1, -1.2, 0.1, 1.0, 0.5};
  std::vector<double> b1 = b0;
  b1[6] -= 0.35 * seconds;
  return {testing::LidarSweep(scene, truth, a0, a1, 0, options, 1),
          testing::LidarSweep(scene, truth, b0, b1, 1, options, 2)};
}

// `count` depth-camera scans of the room from the workspace, 2 mm noise.
std::vector<Dataset> DepthScans(const RobotModel& truth, std::size_t count) {
  const auto configurations = testing::WorkspaceConfigurations(count, 11);
  std::vector<Dataset> datasets;
  for (std::size_t i = 0; i < configurations.size(); ++i) {
    datasets.push_back(testing::DepthScan(testing::RoomScene(), truth, configurations[i], {},
                                          static_cast<int>(i), 0.002,
                                          static_cast<unsigned>(i + 1)));
  }
  return datasets;
}

// The engine's point-to-plane row, contracted with the normal before chaining, is
// n^T ChainPointJacobian (core/model/jacobian.h), the one point derivative.
TEST(PointToPlaneWeights, AgreeWithTheChainedPointJacobian) {
  const RobotModel model = testing::LoadIiwa();
  const std::vector<JointType> types = JointTypes(model);
  const std::vector<double> k = ToParameterVector(model);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> q(model.JointCount());
    for (double& v : q) v = u(rng);
    PoseJacobian J;
    const Eigen::Isometry3d T = ForwardKinematicsWithJacobian(types, k, q, &J);
    const Eigen::Vector3d p_sensor(u(rng), u(rng), 1 + u(rng));
    const Eigen::Vector3d n = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    PointJacobian point;
    ChainPointJacobian(J, T, p_sensor, &point);
    const Eigen::VectorXd chained = point.transpose() * n;
    const Eigen::VectorXd contracted =
        J.transpose() * PointToPlaneWeights(n, T.linear() * p_sensor);
    ASSERT_EQ(contracted.size(), chained.size());
    EXPECT_LT((contracted - chained).cwiseAbs().maxCoeff(), 1e-12) << "trial " << trial;
  }
}

struct Problem {
  RobotModel nominal;
  Chain chain;
  std::vector<double> k_hat;
  std::vector<std::size_t> free;
};

Problem MakeProblem(const std::vector<Dataset>& datasets) {
  Problem setup;
  setup.nominal = testing::LoadIiwa();
  const std::vector<JointType> types = JointTypes(setup.nominal);
  const std::vector<double> k = ToParameterVector(setup.nominal);
  const double scale =
      NormalizationScale(BasePoints(datasets.front(), Chain{types, 1.0, false}, k.data()));
  setup.chain = Chain{types, scale, false};
  setup.k_hat = k;
  NormalizeTranslationParameters(setup.k_hat, types.size(), scale);
  for (std::size_t i = 0; i < setup.nominal.mask.size(); ++i) {
    if (setup.nominal.mask[i]) setup.free.push_back(i);
  }
  return setup;
}

// The direct sums over `matches`, every pose by the full chain (what the fast mode replaces).
NormalEquations DirectSums(const std::vector<Dataset>& datasets, const Chain& chain,
                           const std::vector<FrozenMatch>& matches,
                           const std::vector<std::size_t>& free, const std::vector<double>& k_hat) {
  const long K = static_cast<long>(free.size());
  NormalEquations sums;
  sums.hessian = Eigen::MatrixXd::Zero(K, K);
  sums.gradient = Eigen::VectorXd::Zero(K);
  auto end_of = [&](std::uint32_t d, std::uint32_t point, const Eigen::Vector3d& n,
                    Eigen::VectorXd& row) {
    Transform3<double> T;
    PoseJacobian J;
    chain.PoseWithJacobian(k_hat.data(),
                           datasets[d].pose_joints.data() + datasets[d].PoseOf(point) * 7, T, J);
    const Eigen::Vector3d r = T.linear() * NormalizedSensorPoint(datasets[d], point, chain.scale);
    const Eigen::Vector3d q = r + T.translation();
    Eigen::Matrix<double, 6, 1> w;
    w << n, r.cross(n);
    row.resize(K);
    for (long c = 0; c < K; ++c)
      row[c] = J.col(static_cast<long>(free[static_cast<std::size_t>(c)])).dot(w);
    return q;
  };
  for (const FrozenMatch& match : matches) {
    const Eigen::Vector3d n(match.nx, match.ny, match.nz);
    Eigen::VectorXd row_i, row_j;
    const Eigen::Vector3d q_i = end_of(match.dataset_i, match.point_i, n, row_i);
    const Eigen::Vector3d q_j = end_of(match.dataset_j, match.point_j, n, row_j);
    const double r = n.dot(q_i - q_j);
    const Eigen::VectorXd row = row_i - row_j;
    sums.cost += 0.5 * r * r;
    sums.hessian += row * row.transpose();
    sums.gradient += row * r;
    ++sums.residuals;
  }
  return sums;
}

std::vector<double> Moved(std::vector<double> k_hat, const std::vector<std::size_t>& free,
                          double size) {
  for (std::size_t c = 0; c < free.size(); ++c)
    k_hat[free[c]] += size * std::sin(1.7 * static_cast<double>(c) + 0.3);
  return k_hat;
}

std::vector<PoseKnots> KnotsOf(const std::vector<Dataset>& datasets) {
  std::vector<PoseKnots> knots;
  for (const Dataset& dataset : datasets) knots.push_back(BuildPoseKnots(dataset));
  return knots;
}

TEST(PoseKnots, InterpolatedPosesStayWithinAMicrometreOfTheChain) {
  const RobotModel robot = testing::LoadIiwa();
  const std::vector<Dataset> sweeps = TwoSweeps(robot, 1.0);
  const Dataset& sweep = sweeps.front();
  const PoseKnots knots = BuildPoseKnots(sweep);
  std::printf("%zu poses, %zu knots\n", sweep.PoseCount(), knots.KnotCount());
  EXPECT_LT(knots.KnotCount() * 20, sweep.PoseCount());
  // Encoder noise bends the joint path at every one of the 200 samples per second.
  EXPECT_GE(knots.KnotCount(), 200u);
  std::vector<Eigen::Matrix<double, 3, 4>> at_knot;
  for (std::uint32_t pose : knots.knot_pose) {
    at_knot.push_back(
        ForwardKinematics(robot, std::vector<double>(sweep.pose_joints.data() + pose * 7,
                                                     sweep.pose_joints.data() + pose * 7 + 7))
            .matrix()
            .topRows<3>());
  }
  double worst = 0;
  std::size_t checked = 0;
  for (std::size_t point = 0; point < sweep.PointCount(); ++point) {
    if (!sweep.IsValid(point)) continue;
    const std::vector<double> joints(sweep.pose_joints.data() + point * 7,
                                     sweep.pose_joints.data() + point * 7 + 7);
    const Eigen::Vector3d p(sweep.x[point], sweep.y[point], sweep.z[point]);
    const Eigen::Vector3d exact = ForwardKinematics(robot, joints) * p;
    const std::uint32_t a = knots.segment[point];
    const Eigen::Matrix<double, 3, 4> T =
        Blend(at_knot[a], at_knot[knots.SecondKnot(a)], knots.alpha[point]);
    worst = std::max(worst, (T.leftCols<3>() * p + T.col(3) - exact).norm());
    ++checked;
  }
  std::printf("%zu points, worst interpolation error %.3g m\n", checked, worst);
  EXPECT_GT(checked, 10000u);
  EXPECT_LT(worst, 1e-6);
}

TEST(PoseKnots, SinglePoseScansHaveOneKnot) {
  Dataset dataset;
  dataset.rows = 2;
  dataset.cols = 3;
  dataset.joint_count = 2;
  dataset.pose_joints = {0.1, 0.2};
  const PoseKnots knots = BuildPoseKnots(dataset);
  ASSERT_EQ(knots.KnotCount(), 1u);
  EXPECT_EQ(knots.segment[0], 0u);
  EXPECT_EQ(knots.alpha[0], 0.0f);
}

TEST(MatchProblem, RigidPairFormsEqualTheSumsOverTheirMatches) {
  const RobotModel nominal = testing::LoadIiwa();
  const RobotModel truth = testing::PerturbedModel(nominal, 3);
  const std::vector<Dataset> datasets = DepthScans(truth, 5);
  const Problem setup = MakeProblem(datasets);
  const std::vector<PoseKnots> knots = KnotsOf(datasets);
  CalibrationOptions options;
  options.threads = 2;
  PairMatcher matcher(datasets, setup.chain, knots, options, 2);
  matcher.Prepare(setup.k_hat);
  const std::vector<DatasetPair> pairs = AllPairs(std::vector<bool>(datasets.size(), true));
  // keep_all_matches gives the matches behind the reduced forms.
  MatchProblem problem(datasets, setup.chain, knots, setup.free, 2, true);
  problem.SetMatches(
      pairs, [&](std::size_t p) { return matcher.MatchPair(pairs[p]); }, matcher.clouds(),
      setup.k_hat);
  ASSERT_GT(problem.MatchCount(), 1000u);
  ASSERT_EQ(problem.matches().size(), problem.MatchCount());
  // Away from where they were matched, as the Levenberg-Marquardt steps go.
  const std::vector<double> k_hat = Moved(setup.k_hat, setup.free, 2e-3);
  const NormalEquations fast = problem.Linearize(k_hat);
  const NormalEquations direct =
      DirectSums(datasets, setup.chain, problem.matches(), setup.free, k_hat);
  EXPECT_EQ(fast.residuals, direct.residuals);
  EXPECT_NEAR(fast.cost, direct.cost, 1e-9 * direct.cost);
  EXPECT_LT((fast.hessian - direct.hessian).norm(), 1e-9 * direct.hessian.norm());
  EXPECT_LT((fast.gradient - direct.gradient).norm(), 1e-7 * direct.gradient.norm());
  EXPECT_NEAR(problem.Evaluate(k_hat).cost, fast.cost, 1e-12 * fast.cost);
}

// `count` depth images of the room from the nominal arm, the first two overlapping.
std::vector<Dataset> RoomDepthScans(std::size_t count) {
  const RobotModel nominal = testing::LoadIiwa();
  const auto configurations = testing::WorkspaceConfigurations(count, 11);
  std::vector<Dataset> datasets;
  for (std::size_t i = 0; i < configurations.size(); ++i) {
    datasets.push_back(testing::DepthScan(testing::RoomScene(), nominal, configurations[i], {},
                                          static_cast<int>(i)));
  }
  return datasets;
}

TEST(PairMatcher, QueryStrideMatchesTheSameNeighboursFromEveryNthRowAndColumn) {
  const std::vector<Dataset> datasets = RoomDepthScans(2);
  const Problem setup = MakeProblem(datasets);
  const std::vector<PoseKnots> knots = KnotsOf(datasets);
  CalibrationOptions options;
  PairMatcher every(datasets, setup.chain, knots, options, 1);
  options.query_stride = 2;
  PairMatcher strided(datasets, setup.chain, knots, options, 1);
  every.Prepare(setup.k_hat);
  strided.Prepare(setup.k_hat);
  const PairMatches all = every.MatchPair({0, 1});
  const PairMatches some = strided.MatchPair({0, 1});
  std::size_t on_grid = 0;
  for (std::size_t k = 0; k < all.size(); ++k) {
    const std::uint32_t u = all.point_i[k];
    if ((u / datasets[0].cols) % 2 == 0 && (u % datasets[0].cols) % 2 == 0) ++on_grid;
  }
  ASSERT_GT(all.size(), 200u);
  EXPECT_EQ(some.size(), on_grid);
  for (std::size_t k = 0, a = 0; k < some.size(); ++k) {
    while (a < all.size() && all.point_i[a] != some.point_i[k]) ++a;
    ASSERT_LT(a, all.size()) << "query " << some.point_i[k] << " not matched with every point";
    EXPECT_EQ(all.point_j[a], some.point_j[k]);
  }
}

TEST(PairMatcher, PreparingForSomePairsProjectsOnlyTheirScans) {
  const std::vector<Dataset> datasets = RoomDepthScans(3);
  const Problem setup = MakeProblem(datasets);
  const std::vector<PoseKnots> knots = KnotsOf(datasets);
  const CalibrationOptions options;
  PairMatcher every(datasets, setup.chain, knots, options, 1);
  PairMatcher some(datasets, setup.chain, knots, options, 1);
  every.Prepare(setup.k_hat);
  some.Prepare(setup.k_hat);
  some.Prepare(setup.k_hat, {{0, 1}});
  EXPECT_TRUE(some.clouds()[2].x.empty());
  EXPECT_TRUE(some.clouds()[2].nx.empty());
  // Bit for bit (an invalid point is NaN, which == never equals).
  auto same = [](const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
  };
  for (std::size_t d : {0u, 1u}) {
    EXPECT_TRUE(same(some.clouds()[d].x, every.clouds()[d].x)) << d;
    EXPECT_TRUE(same(some.clouds()[d].nz, every.clouds()[d].nz)) << d;
    EXPECT_EQ(some.clouds()[d].keep, every.clouds()[d].keep) << d;
  }
  const PairMatches expected = every.MatchPair({0, 1});
  const PairMatches matched = some.MatchPair({0, 1});
  ASSERT_GT(expected.size(), 200u);
  EXPECT_EQ(matched.point_i, expected.point_i);
  EXPECT_EQ(matched.point_j, expected.point_j);
  some.Prepare(setup.k_hat, {{1, 2}});
  EXPECT_TRUE(some.clouds()[0].x.empty());
  EXPECT_TRUE(same(some.clouds()[2].x, every.clouds()[2].x));
}

TEST(MatchProblem, MovingScansFollowTheirKnotsAndDifferentiateTheirCost) {
  const RobotModel nominal = testing::LoadIiwa();
  const RobotModel truth = testing::PerturbedModel(nominal, 4);
  const std::vector<Dataset> datasets = TwoSweeps(truth, 1.0);
  const Problem setup = MakeProblem(datasets);
  const std::vector<PoseKnots> knots = KnotsOf(datasets);
  PairMatcher matcher(datasets, setup.chain, knots, testing::HokuyoOptions(), 2);
  matcher.Prepare(setup.k_hat);
  const std::vector<DatasetPair> pairs = {{0, 1}};
  MatchProblem problem(datasets, setup.chain, knots, setup.free, 2, true);
  problem.SetMatches(
      pairs, [&](std::size_t p) { return matcher.MatchPair(pairs[p]); }, matcher.clouds(),
      setup.k_hat);
  ASSERT_GT(problem.MatchCount(), 500u);
  const std::vector<double> k_hat = Moved(setup.k_hat, setup.free, 1e-3);
  const NormalEquations fast = problem.Linearize(k_hat);
  // The cost is the chain's up to the interpolation (a micrometre against residuals of
  // millimetres).
  const NormalEquations direct =
      DirectSums(datasets, setup.chain, problem.matches(), setup.free, k_hat);
  std::printf("%zu matches, cost %.9g (fast) vs %.9g (full chain)\n", fast.residuals, fast.cost,
              direct.cost);
  EXPECT_NEAR(fast.cost, direct.cost, 1e-3 * direct.cost);
  EXPECT_LT((fast.hessian - direct.hessian).norm(), 1e-3 * direct.hessian.norm());
  // And its gradient is the exact derivative of the cost it minimizes: central differences.
  for (std::size_t c = 0; c < setup.free.size(); ++c) {
    const double h = 1e-6;
    std::vector<double> plus = k_hat, minus = k_hat;
    plus[setup.free[c]] += h;
    minus[setup.free[c]] -= h;
    const double numeric = (problem.Evaluate(plus).cost - problem.Evaluate(minus).cost) / (2 * h);
    EXPECT_NEAR(fast.gradient[static_cast<long>(c)], numeric, 1e-5 * fast.gradient.norm() + 1e-12)
        << "parameter " << ParameterName(setup.nominal, setup.free[c]);
  }
}

// With the sensor's intrinsics free (sensor_intrinsics.h, the last columns), the cost
// MatchProblem evaluates is that of the points the change moves, summed match by match, and its
// gradient is that cost's derivative: on moving matches and on rigid pairs.
// `tolerance`: relative, of the cost against the direct sum (the knots' interpolation of moving
// scans: 1e-3, as above).
void ExpectIntrinsicGradient(const std::vector<Dataset>& datasets,
                             const CalibrationOptions& options, const SensorIntrinsics& intrinsics,
                             double tolerance) {
  Problem setup = MakeProblem(datasets);
  setup.chain.intrinsics = intrinsics;
  const std::size_t first = setup.chain.FirstIntrinsic();
  for (std::size_t c = 0; c < intrinsics.Count(); ++c) {
    setup.k_hat.push_back(0.0);
    setup.free.push_back(first + c);
  }
  const std::vector<PoseKnots> knots = KnotsOf(datasets);
  PairMatcher matcher(datasets, setup.chain, knots, options, 2);
  matcher.Prepare(setup.k_hat);
  const std::vector<DatasetPair> pairs = AllPairs(std::vector<bool>(datasets.size(), true));
  MatchProblem problem(datasets, setup.chain, knots, setup.free, 2, true);
  problem.SetMatches(
      pairs, [&](std::size_t p) { return matcher.MatchPair(pairs[p]); }, matcher.clouds(),
      setup.k_hat);
  ASSERT_GT(problem.MatchCount(), 500u);
  // The poses where they were matched (where the rigid pairs' fixed rotations are exact) and
  // the intrinsics changed: the direct sum over the matches of the moved points.
  std::vector<double> changed = setup.k_hat;
  for (std::size_t c = 0; c < intrinsics.Count(); ++c)
    changed[first + c] = 2e-3 * (1.0 + static_cast<double>(c));
  std::vector<Dataset> moved = datasets;
  const IntrinsicValues values =
      intrinsics.Values(setup.chain.FreeIntrinsics(changed.data()), setup.chain.scale);
  for (Dataset& dataset : moved)
    CorrectPoints(intrinsics.measure, IntrinsicValues::Zero(), values, dataset);
  Chain plain = setup.chain;
  plain.intrinsics = {};
  const std::vector<double> mcpc(changed.begin(), changed.begin() + static_cast<long>(first));
  const std::vector<std::size_t> mcpc_free(
      setup.free.begin(), setup.free.end() - static_cast<long>(intrinsics.Count()));
  const NormalEquations direct = DirectSums(moved, plain, problem.matches(), mcpc_free, mcpc);
  EXPECT_NEAR(problem.Evaluate(changed).cost, direct.cost, tolerance * direct.cost);
  EXPECT_GT(std::abs(direct.cost - problem.Evaluate(setup.k_hat).cost), 1e-3 * direct.cost);
  std::vector<double> k_hat = Moved(setup.k_hat, setup.free, 1e-3);
  const NormalEquations fast = problem.Linearize(k_hat);
  EXPECT_NEAR(problem.Evaluate(k_hat).cost, fast.cost, 1e-12 * fast.cost);
  for (std::size_t c = setup.free.size() - intrinsics.Count(); c < setup.free.size(); ++c) {
    const double h = 1e-6;
    std::vector<double> plus = k_hat, minus = k_hat;
    plus[setup.free[c]] += h;
    minus[setup.free[c]] -= h;
    const double numeric = (problem.Evaluate(plus).cost - problem.Evaluate(minus).cost) / (2 * h);
    EXPECT_NEAR(fast.gradient[static_cast<long>(c)], numeric, 1e-5 * fast.gradient.norm() + 1e-12)
        << "intrinsic " << c;
    EXPECT_GT(std::abs(numeric), 0.0) << "intrinsic " << c;
    // Gauss-Newton: the Hessian's diagonal is the squared row's sum (nothing dropped).
    EXPECT_GT(fast.hessian(static_cast<long>(c), static_cast<long>(c)), 0.0);
  }
}

TEST(MatchProblem, IntrinsicColumnsDifferentiateTheCostOfMovingScans) {
  const RobotModel truth = testing::PerturbedModel(testing::LoadIiwa(), 4);
  ExpectIntrinsicGradient(TwoSweeps(truth, 1.0), testing::HokuyoOptions(),
                          SensorIntrinsics{true, true, false, MeasureKind::kRange}, 1e-3);
}

TEST(MatchProblem, IntrinsicColumnsDifferentiateTheCostOfRigidPairs) {
  const RobotModel truth = testing::PerturbedModel(testing::LoadIiwa(), 3);
  const std::vector<Dataset> datasets = DepthScans(truth, 4);
  CalibrationOptions options;
  options.threads = 2;
  ExpectIntrinsicGradient(datasets, options,
                          SensorIntrinsics{true, true, true, MeasureKind::kDepth}, 1e-6);
}

// The expected noise of the matches (rigid_pair.h, deviation 23), directly:
// 1/2 sum sigma^2 (n . R ray)^2 over both ends, every pose by the full chain, the rays of
// `datasets` (corrected as the intrinsics say) in normalized units.
double DirectExpectedNoise(const std::vector<Dataset>& datasets, const Chain& chain,
                           const std::vector<FrozenMatch>& matches, const RayNoise& noise,
                           const std::vector<double>& k_hat) {
  double sum = 0;
  auto end_of = [&](std::uint32_t d, std::uint32_t point, const Eigen::Vector3d& n) {
    const Transform3<double> T = chain.Pose(k_hat.data(), datasets[d].pose_joints.data());
    const Eigen::Vector3d p = NormalizedSensorPoint(datasets[d], point, chain.scale);
    const double sigma = noise.sigma_abs + noise.sigma_rel * p.z();
    const double projected = sigma * n.dot(T.linear() * (p / p.z()));
    return projected * projected;
  };
  for (const FrozenMatch& match : matches) {
    const Eigen::Vector3d n(match.nx, match.ny, match.nz);
    sum += 0.5 *
           (end_of(match.dataset_i, match.point_i, n) + end_of(match.dataset_j, match.point_j, n));
  }
  return sum;
}

// With the ray noise given and the focal length free, a rigid pair's cost is the plain one less
// the fraction NoiseFraction() of the expected noise's change with the focal length; moving the
// poses changes nothing (the rotations' part stays, rigid_pair.h).
TEST(MatchProblem, RayNoiseCorrectionTakesTheExpectedNoiseOutOfRigidPairs) {
  const RobotModel truth = testing::PerturbedModel(testing::LoadIiwa(), 3);
  const std::vector<Dataset> datasets = DepthScans(truth, 4);
  Problem setup = MakeProblem(datasets);
  setup.chain.intrinsics = SensorIntrinsics{false, false, true, MeasureKind::kDepth};
  const std::size_t focal = setup.chain.FirstIntrinsic();
  setup.k_hat.push_back(0.0);
  setup.free.push_back(focal);
  const std::vector<PoseKnots> knots = KnotsOf(datasets);
  CalibrationOptions options;
  PairMatcher matcher(datasets, setup.chain, knots, options, 2);
  matcher.Prepare(setup.k_hat);
  const std::vector<DatasetPair> pairs = AllPairs(std::vector<bool>(datasets.size(), true));
  const RayNoise noise{0.002 / setup.chain.scale, 0.002};
  MatchProblem plain(datasets, setup.chain, knots, setup.free, 2, true);
  MatchProblem corrected(datasets, setup.chain, knots, setup.free, 2, true);
  corrected.SetRayNoise(noise);
  for (MatchProblem* problem : {&plain, &corrected}) {
    problem->SetMatches(
        pairs, [&](std::size_t p) { return matcher.MatchPair(pairs[p]); }, matcher.clouds(),
        setup.k_hat);
  }
  ASSERT_GT(corrected.MatchCount(), 1000u);
  EXPECT_EQ(plain.NoiseFraction(), 0.0);
  // Matched at the perturbed nominal: the residuals exceed the noise, all of it comes out.
  EXPECT_EQ(corrected.NoiseFraction(), 1.0);
  const double v0 =
      DirectExpectedNoise(datasets, setup.chain, corrected.matches(), noise, setup.k_hat);
  EXPECT_EQ(plain.Evaluate(setup.k_hat).cost, corrected.Evaluate(setup.k_hat).cost);

  std::vector<double> moved = Moved(setup.k_hat, setup.free, 2e-3);
  moved[focal] = 0.0;
  EXPECT_EQ(plain.Evaluate(moved).cost, corrected.Evaluate(moved).cost);

  std::vector<double> longer = setup.k_hat;
  longer[focal] = 3e-3;
  std::vector<Dataset> corrected_points = datasets;
  const IntrinsicValues values =
      setup.chain.intrinsics.Values(setup.chain.FreeIntrinsics(longer.data()), setup.chain.scale);
  for (Dataset& dataset : corrected_points)
    CorrectPoints(MeasureKind::kDepth, IntrinsicValues::Zero(), values, dataset);
  const double v_longer =
      DirectExpectedNoise(corrected_points, setup.chain, corrected.matches(), noise, longer);
  ASSERT_GT(std::abs(v_longer - v0), 1e-4 * v0);
  EXPECT_NEAR(plain.Evaluate(longer).cost - corrected.Evaluate(longer).cost, v_longer - v0,
              1e-6 * std::abs(v_longer - v0));
}

}  // namespace
}  // namespace selfcal::calib

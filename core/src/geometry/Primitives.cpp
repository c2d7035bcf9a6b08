// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/geometry/Primitives.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/processing/Normals.h>

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unsupported/Eigen/LevenbergMarquardt>

#include <algorithm>
#include <charconv>
#include <cmath>

namespace scandiff {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::size_t kMaxFitPoints = 200000;

//! A unit vector orthogonal to d, and a third completing a right-handed frame.
void orthonormalFrame(const Eigen::Vector3d& d, Eigen::Vector3d& e1, Eigen::Vector3d& e2)
{
    const Eigen::Vector3d helper = std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    e1 = (helper - helper.dot(d) * d).normalized();
    e2 = d.cross(e1);
}

[[noreturn]] void cannotFit(PrimitiveKind kind, const std::string& why)
{
    throw Error(ErrorCode::InvalidData, std::string("fitting a ") + primitiveKindName(kind) + ": " + why);
}

//! The residual functions of the fits, over points relative to their centroid.
//! Directions are refined as d0 + a e1 + b e2 (normalised), which keeps them
//! unit length without a constraint.
struct Residuals : Eigen::DenseFunctor<double>
{
    Residuals(const std::vector<Eigen::Vector3d>& points, int parameters, std::function<double(const Eigen::VectorXd&, const Eigen::Vector3d&)> f)
        : Eigen::DenseFunctor<double>(parameters, static_cast<int>(points.size())), points_(points), f_(std::move(f))
    {
    }
    //! In parallel over the points (each residual written by one task: the
    //! values do not depend on the threads). The shapes of a scene are fitted
    //! side by side, and the largest fits would otherwise finish on one core.
    int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& residuals) const
    {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points_.size(), 2048), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i)
                residuals[static_cast<Eigen::Index>(i)] = f_(x, points_[i]);
        });
        return 0;
    }
    //! Central differences with a step of 1e-6 (radians for the direction
    //! terms, metres for lengths) or 1e-6 of the parameter when larger.
    //! Eigen's NumericalDiff steps by 1.5e-8 |x|: a parameter that converged
    //! to 1e-17 (a direction term at its start, an offset of nothing) got a
    //! step lost in rounding, a zero column, and a variance of 0 from the
    //! pseudo-inverse (box sides reported 0.002 degrees for 0.04).
    int df(const Eigen::VectorXd& x, Eigen::MatrixXd& jacobian) const
    {
        Eigen::VectorXd shifted = x, plus(values()), minus(values());
        for (Eigen::Index j = 0; j < x.size(); ++j) {
            const double h = 1e-6 * std::max(1.0, std::abs(x[j]));
            shifted[j] = x[j] + h;
            (*this)(shifted, plus);
            shifted[j] = x[j] - h;
            (*this)(shifted, minus);
            shifted[j] = x[j];
            jacobian.col(j) = (plus - minus) / (2 * h);
        }
        // The evaluations it made: Eigen's LM counts them against setMaxfev,
        // as it counted NumericalDiff's.
        return 2 * static_cast<int>(x.size());
    }
    const std::vector<Eigen::Vector3d>& points_;
    std::function<double(const Eigen::VectorXd&, const Eigen::Vector3d&)> f_;
};

//! Levenberg-Marquardt from x, then the parameters' covariance
//! sigma^2 (J^T J)^-1 at the solution (sigma^2 from the residuals).
Eigen::MatrixXd refineWithCovariance(const std::vector<Eigen::Vector3d>& points, Eigen::VectorXd& x,
                                     std::function<double(const Eigen::VectorXd&, const Eigen::Vector3d&)> residual,
                                     PrimitiveKind kind)
{
    if (points.size() < static_cast<std::size_t>(x.size()))
        cannotFit(kind, "too few points");
    Residuals functor(points, static_cast<int>(x.size()), residual);
    Eigen::LevenbergMarquardt<Residuals> lm(functor);
    lm.setFtol(1e-15);
    lm.setXtol(1e-15);
    // A right fit converges within about 20 evaluations a parameter (the
    // 15-shape scene: 106 at most, a torus's seven); a wrong type tried
    // against it (a sphere on a pipe's points) drifts towards an ever larger
    // radius and used all of 400 a parameter, 2,000 passes over 15,000
    // points, the most of the type check's time. It stops at 100 now, still
    // worse than the right type, as it would have ended.
    lm.setMaxfev(100 * static_cast<Eigen::Index>(x.size() + 1));
    lm.minimize(x);
    if (!x.allFinite())
        cannotFit(kind, "the least-squares refinement diverged");
    Eigen::VectorXd r(static_cast<Eigen::Index>(points.size()));
    functor(x, r);
    Eigen::MatrixXd jacobian(static_cast<Eigen::Index>(points.size()), x.size());
    functor.df(x, jacobian);
    // With as many points as parameters the residuals say nothing of the noise (0 here).
    const double variance = r.squaredNorm() / static_cast<double>(std::max<std::size_t>(1, points.size() - static_cast<std::size_t>(x.size())));
    const Eigen::MatrixXd normal = jacobian.transpose() * jacobian;
    return variance * normal.completeOrthogonalDecomposition().pseudoInverse();
}

void refine(const std::vector<Eigen::Vector3d>& points, Eigen::VectorXd& x,
            std::function<double(const Eigen::VectorXd&, const Eigen::Vector3d&)> residual, PrimitiveKind kind)
{
    refineWithCovariance(points, x, std::move(residual), kind);
}


//! The fitted points that have a normal, with it: the cloud's normals, or
//! normals estimated on the whole cloud (plane, 12 neighbours).
void withNormals(const PointCloud& cloud, const std::vector<std::size_t>& used, const std::vector<Eigen::Vector3d>& points,
                 ProgressObserver* progress, std::vector<Eigen::Vector3d>& pairedPoints, std::vector<Eigen::Vector3d>& pairedNormals)
{
    std::vector<Eigen::Vector3f> estimated;
    if (!cloud.hasNormals()) {
        NormalParams params;
        params.knn = 12;
        params.orientation.kind = NormalOrientation::Kind::None;
        estimated = computeNormals(cloud, params, progress).normals;
    }
    const std::vector<Eigen::Vector3f>& all = cloud.hasNormals() ? cloud.normals() : estimated;
    for (std::size_t j = 0; j < used.size(); ++j)
        if (all[used[j]] != Eigen::Vector3f::Zero()) {
            pairedPoints.push_back(points[j]);
            pairedNormals.push_back(all[used[j]].cast<double>().normalized());
        }
}

Eigen::Vector3d smallestAxis(const Eigen::Matrix3d& m)
{
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(m);
    return solver.eigenvectors().col(0);
}

} // namespace

double signedDistance(const Primitive& s, const Eigen::Vector3d& p)
{
    const Eigen::Vector3d v = p - s.point;
    switch (s.kind) {
    case PrimitiveKind::Plane: return v.dot(s.direction);
    case PrimitiveKind::Sphere: return v.norm() - s.radius;
    case PrimitiveKind::Cylinder: return (v - v.dot(s.direction) * s.direction).norm() - s.radius;
    case PrimitiveKind::Cone: {
        const double h = v.dot(s.direction), rho = (v - h * s.direction).norm();
        return rho * std::cos(s.halfAngle) - h * std::sin(s.halfAngle);
    }
    case PrimitiveKind::Torus: {
        const double h = v.dot(s.direction), rho = (v - h * s.direction).norm();
        return std::hypot(rho - s.radius, h) - s.minorRadius;
    }
    }
    return 0;
}

namespace {

//! The points a fit uses: an even sample of at most kMaxFitPoints finite
//! ones, relative to their centroid, in double from the global coordinates
//! (the fit never sees a UTM magnitude).
struct FitSample
{
    std::vector<std::size_t> used; //!< their indices in the cloud
    std::vector<Eigen::Vector3d> points;
    Eigen::Vector3d globalCentroid;
};

FitSample fitSample(const PointCloud& cloud, PrimitiveKind kind)
{
    FitSample sample;
    const std::size_t n = cloud.size();
    const std::size_t stride = (n + kMaxFitPoints - 1) / kMaxFitPoints;
    for (std::size_t i = 0; i < n; i += stride)
        if (cloud.positions()[i].allFinite())
            sample.used.push_back(i);
    if (sample.used.size() < 4)
        cannotFit(kind, "cloud '" + cloud.name + "' has fewer than 4 points with finite coordinates");
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (std::size_t i : sample.used)
        centroid += cloud.positions()[i].cast<double>();
    centroid /= static_cast<double>(sample.used.size());
    sample.points.reserve(sample.used.size());
    for (std::size_t i : sample.used)
        sample.points.push_back(cloud.positions()[i].cast<double>() - centroid);
    sample.globalCentroid = cloud.origin() + centroid;
    return sample;
}

//! The plane through the centroid across the least spread, on a fixed side
//! so the same points always give the same plane.
void fitPlaneTo(const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>& pca, const Eigen::Vector3d& globalCentroid, Primitive& s)
{
    s.point = globalCentroid;
    s.direction = pca.eigenvectors().col(0).normalized();
    // A fixed side, so the same points always give the same plane: +Z
    // first, then +Y, then +X.
    const Eigen::Vector3d d = s.direction;
    const double key = std::abs(d.z()) > 1e-9 ? d.z() : std::abs(d.y()) > 1e-9 ? d.y() : d.x();
    if (key < 0)
        s.direction = -s.direction;
}

//! The algebraic sphere, refined by least squares on the distances.
void fitSphereTo(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& globalCentroid, Primitive& s)
{
    const PrimitiveKind kind = PrimitiveKind::Sphere;
    const std::optional<Primitive> algebraic = algebraicSphere(points, globalCentroid);
    if (!algebraic)
        cannotFit(kind, "the points do not determine a sphere");
    Eigen::VectorXd x(4);
    x << algebraic->point - globalCentroid, algebraic->radius;
    refine(points, x, [](const Eigen::VectorXd& x, const Eigen::Vector3d& p) { return (p - x.head<3>()).norm() - x[3]; }, kind);
    s.point = globalCentroid + x.head<3>();
    s.radius = std::abs(x[3]);
}

//! The axis from the normals, refined by least squares on the distances.
void fitCylinderTo(const PointCloud& cloud, const FitSample& sample, ProgressObserver* progress, Primitive& s)
{
    const PrimitiveKind kind = PrimitiveKind::Cylinder;
    const std::vector<Eigen::Vector3d>& points = sample.points;
    const Eigen::Vector3d& globalCentroid = sample.globalCentroid;
    // Every normal of a cylinder is orthogonal to its axis.
    std::vector<Eigen::Vector3d> pairedPoints, normals;
    withNormals(cloud, sample.used, points, progress, pairedPoints, normals);
    if (normals.size() < 5)
        cannotFit(kind, "too few points with a normal");
    const std::optional<Primitive> start = cylinderFromNormals(points, normals, Eigen::Vector3d::Zero());
    if (!start)
        cannotFit(kind, "the points do not determine a circle across the axis");
    const Eigen::Vector3d d0 = start->direction;
    Eigen::Vector3d e1, e2;
    orthonormalFrame(d0, e1, e2);
    Eigen::VectorXd x(5);
    x << start->point.dot(e1), start->point.dot(e2), 0, 0, start->radius;
    const auto axisOf = [d0, e1, e2](const Eigen::VectorXd& x) { return (d0 + x[2] * e1 + x[3] * e2).normalized(); };
    refine(points, x, [&](const Eigen::VectorXd& x, const Eigen::Vector3d& p) {
        const Eigen::Vector3d d = axisOf(x), v = p - (x[0] * e1 + x[1] * e2);
        return (v - v.dot(d) * d).norm() - x[4];
    }, kind);
    const Eigen::Vector3d d = axisOf(x), onAxis = x[0] * e1 + x[1] * e2;
    s.direction = d;
    s.point = globalCentroid + onAxis - onAxis.dot(d) * d; // the foot of the centroid
    s.radius = std::abs(x[4]);
}

//! The apex and axis from the normals, refined by least squares.
void fitConeTo(const PointCloud& cloud, const FitSample& sample, ProgressObserver* progress, Primitive& s)
{
    const PrimitiveKind kind = PrimitiveKind::Cone;
    const std::vector<Eigen::Vector3d>& points = sample.points;
    const Eigen::Vector3d& globalCentroid = sample.globalCentroid;
    // A cone's normals make one angle with its axis (the axis is the
    // direction along which they vary least), and each normal's plane
    // through its point holds the apex.
    std::vector<Eigen::Vector3d> pairedPoints, pairedNormals;
    withNormals(cloud, sample.used, points, progress, pairedPoints, pairedNormals);
    if (pairedNormals.size() < 6)
        cannotFit(kind, "too few points with a normal");
    // Normals are unoriented: each turned to the side of the first before they are compared.
    std::vector<Eigen::Vector3d> aligned = pairedNormals;
    for (auto& nrm : aligned)
        if (nrm.dot(aligned.front()) < 0)
            nrm = -nrm;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& nrm : aligned)
        mean += nrm;
    mean /= static_cast<double>(aligned.size());
    Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
    for (const auto& nrm : aligned)
        spread.noalias() += (nrm - mean) * (nrm - mean).transpose();
    Eigen::Vector3d d0 = smallestAxis(spread);
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (std::size_t j = 0; j < pairedPoints.size(); ++j) {
        a.noalias() += pairedNormals[j] * pairedNormals[j].transpose();
        b += pairedNormals[j] * pairedNormals[j].dot(pairedPoints[j]);
    }
    const Eigen::Vector3d apex0 = a.ldlt().solve(b);
    if (!apex0.allFinite())
        cannotFit(kind, "the normals do not meet at an apex");
    double along = 0;
    for (const auto& p : points)
        along += (p - apex0).dot(d0);
    if (along < 0)
        d0 = -d0;
    double angle = 0;
    for (const auto& p : points) {
        const Eigen::Vector3d v = p - apex0;
        const double h = v.dot(d0);
        angle += std::atan2((v - h * d0).norm(), h);
    }
    angle /= static_cast<double>(points.size());
    Eigen::Vector3d e1, e2;
    orthonormalFrame(d0, e1, e2);
    Eigen::VectorXd x(6);
    x << apex0, 0, 0, angle;
    const auto axisOf = [d0, e1, e2](const Eigen::VectorXd& x) { return (d0 + x[3] * e1 + x[4] * e2).normalized(); };
    refine(points, x, [&](const Eigen::VectorXd& x, const Eigen::Vector3d& p) {
        const Eigen::Vector3d d = axisOf(x), v = p - x.head<3>();
        const double h = v.dot(d), rho = (v - h * d).norm();
        return rho * std::cos(x[5]) - h * std::sin(x[5]);
    }, kind);
    s.point = globalCentroid + x.head<3>();
    s.direction = axisOf(x);
    s.halfAngle = x[5];
    if (!(s.halfAngle > 0 && s.halfAngle < kPi / 2))
        cannotFit(kind, "the fitted half-angle is not between 0 and 90 degrees");
}

//! The root mean square of the signed distances of every finite point.
double rmsDistance(const PointCloud& cloud, const Primitive& s)
{
    double sum = 0;
    std::size_t finite = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const double d = signedDistance(s, cloud.globalPosition(i));
        if (std::isfinite(d)) {
            sum += d * d;
            ++finite;
        }
    }
    return std::sqrt(sum / static_cast<double>(finite));
}

} // namespace

PrimitiveFit fitPrimitive(const PointCloud& cloud, PrimitiveKind kind, ProgressObserver* progress)
{
    if (cloud.size() < 4)
        cannotFit(kind, "cloud '" + cloud.name + "' has fewer than 4 points");
    ProgressTicker ticker(progress, std::string("Fitting a ") + primitiveKindName(kind), 3);
    const FitSample sample = fitSample(cloud, kind);
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const auto& p : sample.points)
        covariance.noalias() += p * p.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(covariance);
    if (!(pca.eigenvalues()[1] > 1e-12 * pca.eigenvalues()[2]))
        cannotFit(kind, "the points are (nearly) on a line");
    ticker.step();

    Primitive s;
    s.kind = kind;
    switch (kind) {
    case PrimitiveKind::Plane: fitPlaneTo(pca, sample.globalCentroid, s); break;
    case PrimitiveKind::Sphere: fitSphereTo(sample.points, sample.globalCentroid, s); break;
    case PrimitiveKind::Cylinder: fitCylinderTo(cloud, sample, progress, s); break;
    case PrimitiveKind::Cone: fitConeTo(cloud, sample, progress, s); break;
    case PrimitiveKind::Torus:
        throw Error(ErrorCode::Unsupported, "a torus is fitted from a detected one (primitive extraction), not from scratch");
    }
    ticker.step();
    PrimitiveFit fit;
    fit.primitive = s;
    fit.points = sample.used.size();
    fit.rms = rmsDistance(cloud, s);
    ticker.step();
    return fit;
}

PrimitiveKind parsePrimitiveKind(const std::string& name)
{
    if (name == "plane")
        return PrimitiveKind::Plane;
    if (name == "sphere")
        return PrimitiveKind::Sphere;
    if (name == "cylinder")
        return PrimitiveKind::Cylinder;
    if (name == "cone")
        return PrimitiveKind::Cone;
    if (name == "torus")
        return PrimitiveKind::Torus;
    throw Error(ErrorCode::InvalidArgument, "'" + name + "' is not plane, sphere, cylinder, cone or torus");
}

const char* primitiveKindName(PrimitiveKind kind)
{
    switch (kind) {
    case PrimitiveKind::Plane: return "plane";
    case PrimitiveKind::Sphere: return "sphere";
    case PrimitiveKind::Cylinder: return "cylinder";
    case PrimitiveKind::Cone: return "cone";
    case PrimitiveKind::Torus: return "torus";
    }
    return "";
}

Primitive parsePrimitive(const std::string& text)
{
    const auto colon = text.find(':');
    if (colon == std::string::npos)
        throw Error(ErrorCode::InvalidArgument, "primitive '" + text + "' is not KIND:NUMBERS (e.g. cylinder:PX,PY,PZ,DX,DY,DZ,R)");
    Primitive s;
    s.kind = parsePrimitiveKind(text.substr(0, colon));
    const std::vector<double> v = parseNumberList(text.substr(colon + 1), "the primitive's numbers");
    const std::size_t expected = s.kind == PrimitiveKind::Sphere ? 4 : s.kind == PrimitiveKind::Plane ? 6 : s.kind == PrimitiveKind::Torus ? 8 : 7;
    if (v.size() != expected)
        throw Error(ErrorCode::InvalidArgument, std::string("a ") + primitiveKindName(s.kind) + " takes " + std::to_string(expected) +
                                                    " numbers, not " + std::to_string(v.size()));
    s.point = Eigen::Vector3d(v[0], v[1], v[2]);
    if (s.kind == PrimitiveKind::Sphere) {
        s.radius = v[3];
    } else {
        s.direction = Eigen::Vector3d(v[3], v[4], v[5]);
        if (!(s.direction.norm() > 0))
            throw Error(ErrorCode::InvalidArgument, "the primitive's direction must not be zero");
        s.direction.normalize();
        if (s.kind == PrimitiveKind::Cylinder || s.kind == PrimitiveKind::Torus)
            s.radius = v[6];
        if (s.kind == PrimitiveKind::Torus)
            s.minorRadius = v[7];
        if (s.kind == PrimitiveKind::Cone)
            s.halfAngle = v[6] * kPi / 180.0;
    }
    if (s.kind == PrimitiveKind::Torus && !(s.minorRadius > 0))
        throw Error(ErrorCode::InvalidArgument, "the torus's minor radius must be > 0");
    if ((s.kind == PrimitiveKind::Sphere || s.kind == PrimitiveKind::Cylinder || s.kind == PrimitiveKind::Torus) && !(s.radius > 0))
        throw Error(ErrorCode::InvalidArgument, "the primitive's radius must be > 0");
    if (s.kind == PrimitiveKind::Cone && !(s.halfAngle > 0 && s.halfAngle < kPi / 2))
        throw Error(ErrorCode::InvalidArgument, "the cone's half-angle must be between 0 and 90 degrees");
    return s;
}

std::string primitiveText(const Primitive& s)
{
    std::string text = std::string(primitiveKindName(s.kind)) + ":";
    const auto add = [&](double v, bool last = false) {
        char buffer[32];
        const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
        text.append(buffer, r.ptr);
        if (!last)
            text += ',';
    };
    add(s.point.x());
    add(s.point.y());
    add(s.point.z());
    if (s.kind == PrimitiveKind::Sphere) {
        add(s.radius, true);
        return text;
    }
    add(s.direction.x());
    add(s.direction.y());
    add(s.direction.z(), s.kind == PrimitiveKind::Plane);
    if (s.kind == PrimitiveKind::Cylinder)
        add(s.radius, true);
    if (s.kind == PrimitiveKind::Cone)
        add(s.halfAngle * 180.0 / kPi, true);
    if (s.kind == PrimitiveKind::Torus) {
        add(s.radius);
        add(s.minorRadius, true);
    }
    return text;
}

Table primitiveTable(const Primitive& s, std::optional<double> rms)
{
    Table t;
    t.columns = {"parameter", "value"};
    t.rows.push_back({std::string("kind"), std::string(primitiveKindName(s.kind))});
    const char* pointName = s.kind == PrimitiveKind::Sphere || s.kind == PrimitiveKind::Torus ? "centre"
                            : s.kind == PrimitiveKind::Cone                                   ? "apex"
                                                                                              : "point";
    for (int a = 0; a < 3; ++a)
        t.rows.push_back({std::string(pointName) + "_" + "xyz"[a], s.point[a]});
    if (s.kind != PrimitiveKind::Sphere)
        for (int a = 0; a < 3; ++a)
            t.rows.push_back({std::string(s.kind == PrimitiveKind::Plane ? "normal_" : "axis_") + "xyz"[a], s.direction[a]});
    if (s.kind == PrimitiveKind::Sphere || s.kind == PrimitiveKind::Cylinder)
        t.rows.push_back({std::string("radius"), s.radius});
    if (s.kind == PrimitiveKind::Torus) {
        t.rows.push_back({std::string("major_radius"), s.radius});
        t.rows.push_back({std::string("minor_radius"), s.minorRadius});
    }
    if (s.kind == PrimitiveKind::Cone)
        t.rows.push_back({std::string("half_angle_deg"), s.halfAngle * 180.0 / kPi});
    if (rms)
        t.rows.push_back({std::string("rms"), *rms});
    t.rows.push_back({std::string("text"), primitiveText(s)});
    return t;
}

} // namespace scandiff

namespace scandiff {

bool fitCircle(const std::vector<Eigen::Vector2d>& p, Eigen::Vector2d& centre, double& radius)
{
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (const auto& q : p) {
        const Eigen::Vector3d row(2 * q.x(), 2 * q.y(), 1);
        a.noalias() += row * row.transpose();
        b += row * q.squaredNorm();
    }
    const Eigen::Vector3d s = a.ldlt().solve(b);
    centre = s.head<2>();
    radius = std::sqrt(s[2] + centre.squaredNorm());
    return s.allFinite() && radius > 0;
}


std::optional<Primitive> cylinderFromNormals(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                                             const Eigen::Vector3d& centre)
{
    if (normals.size() < 5 || points.size() < 5)
        return std::nullopt;
    // Every normal of a cylinder is orthogonal to its axis.
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    for (const auto& n : normals)
        m.noalias() += n * n.transpose();
    const Eigen::Vector3d axis = smallestAxis(m);
    Eigen::Vector3d e1, e2;
    orthonormalFrame(axis, e1, e2);
    std::vector<Eigen::Vector2d> planar;
    planar.reserve(points.size());
    for (const auto& p : points)
        planar.emplace_back(p.dot(e1), p.dot(e2));
    Eigen::Vector2d circleCentre;
    double radius = 0;
    if (!fitCircle(planar, circleCentre, radius))
        return std::nullopt;
    Primitive cylinder;
    cylinder.kind = PrimitiveKind::Cylinder;
    cylinder.direction = axis;
    cylinder.point = centre + circleCentre.x() * e1 + circleCentre.y() * e2;
    cylinder.radius = radius;
    return cylinder;
}

std::optional<Primitive> algebraicSphere(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& centre)
{
    Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
    Eigen::Vector4d b = Eigen::Vector4d::Zero();
    for (const auto& p : points) {
        const Eigen::Vector4d row(2 * p.x(), 2 * p.y(), 2 * p.z(), 1);
        a.noalias() += row * row.transpose();
        b += row * p.squaredNorm();
    }
    const Eigen::Vector4d s = a.ldlt().solve(b);
    const double r2 = s[3] + s.head<3>().squaredNorm();
    if (!s.allFinite() || !(r2 > 0))
        return std::nullopt;
    Primitive sphere;
    sphere.kind = PrimitiveKind::Sphere;
    sphere.point = centre + s.head<3>();
    sphere.radius = std::sqrt(r2);
    return sphere;
}

PrimitiveRefinement refinePrimitive(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& centre,
                                    const Primitive& initial)
{
    const PrimitiveKind kind = initial.kind;
    // At most this many points, evenly spread, enter the solver; the
    // uncertainties are scaled to the whole set (independent residuals).
    constexpr std::size_t kMaxRefinePoints = 20000;
    std::vector<Eigen::Vector3d> used;
    const std::size_t stride = (points.size() + kMaxRefinePoints - 1) / std::max<std::size_t>(kMaxRefinePoints, 1);
    for (std::size_t i = 0; i < points.size(); i += std::max<std::size_t>(stride, 1))
        used.push_back(points[i]);
    const double scale = std::sqrt(static_cast<double>(used.size()) / static_cast<double>(std::max<std::size_t>(points.size(), 1)));
    const Eigen::Vector3d d0 = initial.direction.normalized();
    Eigen::Vector3d e1, e2;
    orthonormalFrame(d0, e1, e2);
    const Eigen::Vector3d p0 = initial.point - centre;
    const auto directionOf = [&](double a, double b) { return Eigen::Vector3d(d0 + a * e1 + b * e2).normalized(); };
    const auto sigma = [&](const Eigen::MatrixXd& cov, std::initializer_list<Eigen::Index> indices) {
        double sum = 0;
        for (Eigen::Index i : indices)
            sum += std::max(cov(i, i), 0.0);
        return std::sqrt(sum) * scale;
    };
    constexpr double kDegrees = 180.0 / kPi;
    PrimitiveRefinement out;
    Primitive& s = out.primitive;
    s = initial;
    switch (kind) {
    case PrimitiveKind::Plane: {
        Eigen::VectorXd x = Eigen::VectorXd::Zero(3);
        const Eigen::MatrixXd cov = refineWithCovariance(used, x, [&](const Eigen::VectorXd& x, const Eigen::Vector3d& p) {
            return (p - p0).dot(directionOf(x[0], x[1])) - x[2];
        }, kind);
        s.direction = directionOf(x[0], x[1]);
        s.point = centre + p0 + x[2] * s.direction;
        out.uncertainty = {{"direction_deg", sigma(cov, {0, 1}) * kDegrees}, {"offset", sigma(cov, {2})}};
        break;
    }
    case PrimitiveKind::Sphere: {
        Eigen::VectorXd x(4);
        x << p0, initial.radius;
        const Eigen::MatrixXd cov = refineWithCovariance(used, x, [](const Eigen::VectorXd& x, const Eigen::Vector3d& p) {
            return (p - x.head<3>()).norm() - x[3];
        }, kind);
        s.point = centre + x.head<3>();
        s.radius = std::abs(x[3]);
        out.uncertainty = {{"centre", sigma(cov, {0, 1, 2})}, {"radius", sigma(cov, {3})}};
        break;
    }
    case PrimitiveKind::Cylinder: {
        Eigen::VectorXd x(5);
        x << 0, 0, 0, 0, initial.radius;
        const Eigen::MatrixXd cov = refineWithCovariance(used, x, [&](const Eigen::VectorXd& x, const Eigen::Vector3d& p) {
            const Eigen::Vector3d d = directionOf(x[2], x[3]), v = p - (p0 + x[0] * e1 + x[1] * e2);
            return (v - v.dot(d) * d).norm() - x[4];
        }, kind);
        s.direction = directionOf(x[2], x[3]);
        const Eigen::Vector3d onAxis = p0 + x[0] * e1 + x[1] * e2;
        s.point = centre + onAxis - onAxis.dot(s.direction) * s.direction; // the foot of the centre
        s.radius = std::abs(x[4]);
        out.uncertainty = {{"direction_deg", sigma(cov, {2, 3}) * kDegrees}, {"axis_position", sigma(cov, {0, 1})}, {"radius", sigma(cov, {4})}};
        break;
    }
    case PrimitiveKind::Cone: {
        Eigen::VectorXd x(6);
        x << p0, 0, 0, initial.halfAngle;
        const Eigen::MatrixXd cov = refineWithCovariance(used, x, [&](const Eigen::VectorXd& x, const Eigen::Vector3d& p) {
            const Eigen::Vector3d d = directionOf(x[3], x[4]), v = p - x.head<3>();
            const double h = v.dot(d), rho = (v - h * d).norm();
            return rho * std::cos(x[5]) - h * std::sin(x[5]);
        }, kind);
        s.point = centre + x.head<3>();
        s.direction = directionOf(x[3], x[4]);
        s.halfAngle = x[5];
        if (!(s.halfAngle > 0 && s.halfAngle < kPi / 2))
            cannotFit(kind, "the fitted half-angle is not between 0 and 90 degrees");
        out.uncertainty = {{"apex", sigma(cov, {0, 1, 2})}, {"direction_deg", sigma(cov, {3, 4}) * kDegrees},
                           {"half_angle_deg", sigma(cov, {5}) * kDegrees}};
        break;
    }
    case PrimitiveKind::Torus: {
        Eigen::VectorXd x(7);
        x << p0, 0, 0, initial.radius, initial.minorRadius;
        const Eigen::MatrixXd cov = refineWithCovariance(used, x, [&](const Eigen::VectorXd& x, const Eigen::Vector3d& p) {
            const Eigen::Vector3d d = directionOf(x[3], x[4]), v = p - x.head<3>();
            const double h = v.dot(d), rho = (v - h * d).norm();
            return std::hypot(rho - x[5], h) - x[6];
        }, kind);
        s.point = centre + x.head<3>();
        s.direction = directionOf(x[3], x[4]);
        s.radius = std::abs(x[5]);
        s.minorRadius = std::abs(x[6]);
        out.uncertainty = {{"centre", sigma(cov, {0, 1, 2})}, {"direction_deg", sigma(cov, {3, 4}) * kDegrees},
                           {"radius", sigma(cov, {5})}, {"minor_radius", sigma(cov, {6})}};
        break;
    }
    }
    double sum = 0;
    for (const Eigen::Vector3d& p : points) {
        const double d = signedDistance(s, centre + p);
        sum += d * d;
    }
    out.rms = points.empty() ? 0 : std::sqrt(sum / static_cast<double>(points.size()));
    return out;
}

} // namespace scandiff

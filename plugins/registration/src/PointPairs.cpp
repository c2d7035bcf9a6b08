// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/registration/PointPairs.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace scandiff::plugins {

RegistrationReport fitPointPairs(const std::vector<PointPair>& pairs, const DofConstraint& constraint)
{
    const std::size_t needed = constraint.dof == Dof::Six ? 3 : constraint.dof == Dof::Four ? 2 : 1;
    if (pairs.size() < needed)
        throw Error(ErrorCode::InvalidArgument, "point pairs: at least " + std::to_string(needed) + " pairs for " + dofName(constraint.dof) +
                                                    " degrees of freedom, " + std::to_string(pairs.size()) + " given");
    // In a frame centred on the reference points: georeferenced magnitudes
    // stay out of the products.
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    for (const auto& p : pairs)
        origin += p.reference;
    origin /= static_cast<double>(pairs.size());
    std::vector<Eigen::Vector3d> x, y;
    for (const auto& p : pairs) {
        if (!p.moving.allFinite() || !p.reference.allFinite())
            throw Error(ErrorCode::InvalidArgument, "point pairs: a pair has a coordinate that is not a finite number");
        x.push_back(p.moving - origin);
        y.push_back(p.reference - origin);
    }
    const std::vector<double> w(pairs.size(), 1.0);
    Eigen::Isometry3d motion;
    if (!fitPointToPoint(x, y, w, constraint, motion))
        throw Error(ErrorCode::InvalidArgument, "point pairs: the pairs do not fix a motion (all on a line, or coincident)");
    RegistrationReport report;
    report.method = std::string("point pairs, ") + dofName(constraint.dof) + " DOF";
    report.matrix = toGlobal(motion, origin);
    for (const auto& p : pairs)
        report.centre += p.moving / static_cast<double>(pairs.size());
    double sum2 = 0;
    for (std::size_t i = 0; i < pairs.size(); ++i) {
        const double r = (motion * x[i] - y[i]).norm();
        report.pairResiduals.push_back(r);
        sum2 += r * r;
    }
    report.rms = std::sqrt(sum2 / static_cast<double>(pairs.size()));
    report.median = report.p90 = report.p95 = report.p99 = std::numeric_limits<double>::quiet_NaN();
    report.overlap = 1.0;
    report.converged = true;
    // Three pairs for six unknowns (two for four) still check each other
    // through their distances; one pair for a translation does not.
    if (constraint.dof == Dof::Translation && pairs.size() == 1)
        report.notes.push_back("one pair fixes a translation exactly: its residual says nothing of the error; add pairs to check");
    return report;
}

std::vector<PointPair> parsePointPairs(const std::string& text)
{
    std::string content = text;
    if (std::ifstream file{text}) {
        std::stringstream all;
        all << file.rdbuf();
        content = all.str();
    }
    std::vector<PointPair> pairs;
    std::string line;
    for (char& c : content)
        if (c == ';' || c == '\r')
            c = '\n';
    std::istringstream lines(content);
    bool first = true;
    while (std::getline(lines, line)) {
        std::string numbers = line;
        for (char& c : numbers)
            if (c == ' ' || c == '\t')
                c = ',';
        std::vector<double> v;
        for (const std::string& part : splitList(numbers, ','))
            if (!part.empty()) {
                try {
                    v.push_back(parseNumberList(part, "a point pair").front());
                } catch (const Error&) {
                    v.clear();
                    if (first) // a header line
                        break;
                    throw Error(ErrorCode::InvalidArgument, "point pairs: '" + line + "' is not 6 numbers");
                }
            }
        first = false;
        if (v.empty())
            continue;
        if (v.size() != 6)
            throw Error(ErrorCode::InvalidArgument, "point pairs: '" + line + "' is not 6 numbers (MX,MY,MZ,RX,RY,RZ)");
        pairs.push_back({Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5])});
    }
    return pairs;
}

} // namespace scandiff::plugins

// Two-parameter curves in HDF5 and JSON (see include/vibro/curve_output.hpp).
#include "vibro/curve_output.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace vibro {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Lead(const std::vector<std::complex<double>>& mu) {
  double l = mu.empty() ? kNaN : 0.0;
  for (const auto& m : mu) l = std::max(l, std::abs(m));
  return l;
}

}  // namespace

void WriteCurves(Hdf5Store& store, const std::string& param1, const std::string& param2,
                 const std::vector<Curve>& curves) {
  H5Table top;
  top.text = {{"param1", param1}, {"param2", param2}};
  top.integers = {{"count", static_cast<long long>(curves.size())}};
  store.WriteTable("/curves", top);
  for (size_t c = 0; c < curves.size(); ++c) {
    const Curve& cv = curves[c];
    const size_t N = cv.points.size();
    size_t m = 1, n = 0;
    for (const auto& p : cv.points) {
      m = std::max(m, p.multipliers.size());
      n = std::max(n, static_cast<size_t>(p.X.size()));
    }
    std::vector<double> v1, v2, br, o1, o2, t0, stable, lead, rot, mu(N * m * 2, kNaN), X(N * n, kNaN), V(N * n, kNaN);
    std::vector<std::string> events, sequence, detail;
    for (size_t i = 0; i < N; ++i) {
      const auto& p = cv.points[i];
      v1.push_back(p.value1);
      v2.push_back(p.value2);
      br.push_back(p.bracket);
      o1.push_back(p.orbit1);
      o2.push_back(p.orbit2);
      t0.push_back(p.section_time);
      stable.push_back(p.stable ? 1 : 0);
      lead.push_back(Lead(p.multipliers));
      rot.push_back(p.rotation_number);
      for (size_t j = 0; j < p.multipliers.size(); ++j) {
        mu[(i * m + j) * 2] = p.multipliers[j].real();
        mu[(i * m + j) * 2 + 1] = p.multipliers[j].imag();
      }
      for (Eigen::Index j = 0; j < p.X.size(); ++j) {
        X[i * n + static_cast<size_t>(j)] = p.X[j];
        V[i * n + static_cast<size_t>(j)] = p.V[j];
      }
      events.push_back(p.signature);
      sequence.push_back(p.sequence);
      detail.push_back(p.detail);
    }
    H5Table t;
    const auto col = [&](const char* name, std::vector<double> v, char type = 'f') {
      const size_t rows = v.size();
      t.arrays.push_back({name, {rows}, std::move(v), type});
    };
    col("value1", v1);
    col("value2", v2);
    col("bracket", br);
    col("orbit1", o1);
    col("orbit2", o2);
    col("section_time", t0);
    col("stable", stable, 'u');
    col("max_multiplier", lead);
    col("rotation_number", rot);
    t.arrays.push_back({"multipliers", {N, m, 2}, mu});
    t.arrays.push_back({"X", {N, n}, X});
    t.arrays.push_back({"V", {N, n}, V});
    t.strings = {{"events", events}, {"sequence", sequence}, {"detail", detail}};
    t.text = {{"kind", cv.kind}, {"status", cv.status}, {"end_start", cv.end_start}, {"end_finish", cv.end_finish}};
    t.integers = {{"contact", cv.contact}, {"period", cv.period}, {"corrections", cv.corrections}};
    const std::string group = fmt::format("/curves/{:03d}", c);
    store.WriteTable(group, t);
    H5Table s;
    std::vector<double> sv1, sv2, sb, sa;
    std::vector<std::string> sk, sd;
    for (const auto& x : cv.special) {
      sv1.push_back(x.value1);
      sv2.push_back(x.value2);
      sb.push_back(x.bracket);
      sa.push_back(static_cast<double>(x.after));
      sk.push_back(x.kind);
      sd.push_back(x.detail);
    }
    s.arrays = {{"value1", {sv1.size()}, sv1}, {"value2", {sv2.size()}, sv2}, {"bracket", {sb.size()}, sb},
                {"after", {sa.size()}, sa, 'i'}};
    s.strings = {{"kind", sk}, {"detail", sd}};
    store.WriteTable(group + "/special", s);
  }
}

std::string CurvesJson(const std::string& param1, const std::string& param2, const std::vector<Curve>& curves) {
  nlohmann::json j;
  j["params"] = {param1, param2};
  auto list = nlohmann::json::array();
  for (const auto& cv : curves) {
    auto pts = nlohmann::json::array();
    for (const auto& p : cv.points) {
      nlohmann::json o = {{"value1", p.value1}, {"value2", p.value2}, {"bracket", p.bracket}, {"stable", p.stable},
                          {"events", p.signature}, {"sequence", p.sequence}};
      const double l = Lead(p.multipliers);
      o["max_multiplier"] = std::isfinite(l) ? nlohmann::json(l) : nlohmann::json(nullptr);
      if (std::isfinite(p.rotation_number)) o["rotation_number"] = p.rotation_number;
      pts.push_back(o);
    }
    auto sp = nlohmann::json::array();
    for (const auto& x : cv.special)
      sp.push_back({{"kind", x.kind}, {"value1", x.value1}, {"value2", x.value2}, {"bracket", x.bracket},
                    {"after", x.after}, {"detail", x.detail}});
    list.push_back({{"kind", cv.kind},
                    {"contact", cv.contact},
                    {"period", cv.period},
                    {"status", cv.status},
                    {"end_start", cv.end_start},
                    {"end_finish", cv.end_finish},
                    {"corrections", cv.corrections},
                    {"points", pts},
                    {"special", sp}});
  }
  j["curves"] = list;
  return j.dump();
}

}  // namespace vibro

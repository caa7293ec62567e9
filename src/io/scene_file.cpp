// TOML scene files (docs/scenes.md). The one file of vibro that includes toml++.
//
// Flow: parse the file → apply each `--set KEY=VALUE` (VALUE in TOML syntax) → check the key
// schema (unknown keys, types, finiteness) → fill a Scene → Validate() the physics. Problems of
// every stage are collected and reported together, each located at the node it concerns.
#include "vibro/scene_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

namespace vibro {
namespace {

std::string ShortestFloats(const std::string& text);

// Limits applied before toml++ sees any text: its parser recurses on nesting and on the
// components of dotted keys, so deep input would overflow the stack.
constexpr size_t kMaxSceneBytes = 1 << 20;  // 1 MiB
constexpr int kMaxNesting = 32;             // [ and { open at once
constexpr int kMaxKeyComponents = 16;       // a.b.c... in one key or table header
constexpr long long kMaxIndex = 1 << 20;    // DOF indices and mode counts (int after checking)

// The first violation of the limits above in `text` ("" when none), located as file:line:col.
// A light scan of TOML's lexical structure: strings (basic, literal, multi-line) and comments are
// skipped; brackets outside them count as nesting; a run of key characters and dots (newline, =,
// comma and brackets end it) counts the components of a dotted key.
std::string PreScan(std::string_view text, const std::string& source) {
  if (text.size() > kMaxSceneBytes)
    return fmt::format("{}: larger than {} bytes: not a scene file", source, kMaxSceneBytes);
  int depth = 0, dots = 0, line = 1;
  size_t line_start = 0;
  const auto where = [&](size_t i) { return fmt::format("{}:{}:{}", source, line, i - line_start + 1); };
  for (size_t i = 0; i < text.size(); ++i) {
    const char ch = text[i];
    if (ch == '\0') return where(i) + ": a NUL byte: not a text file";
    if (ch == '\n') {
      ++line;
      line_start = i + 1;
      dots = 0;
      continue;
    }
    if (ch == '#') {
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
      continue;
    }
    if (ch == '"' || ch == '\'') {
      const bool triple = text.substr(i, 3) == std::string(3, ch);
      const size_t open = i;
      i += triple ? 3 : 1;
      for (; i < text.size(); ++i) {
        if (text[i] == '\n') {
          if (!triple) break;  // an unterminated string: toml++ reports it
          ++line;
          line_start = i + 1;
        }
        if (ch == '"' && text[i] == '\\') {
          ++i;
          continue;
        }
        if (text[i] == ch && (!triple || text.substr(i, 3) == std::string(3, ch))) {
          if (triple) i += 2;
          break;
        }
      }
      if (i >= text.size()) return {};  // unterminated: toml++ says so
      if (text[i] == '\n') --i;
      (void)open;
      continue;
    }
    if (ch == '[' || ch == '{') {
      if (++depth > kMaxNesting)
        return where(i) + fmt::format(": nesting deeper than {} levels of [ and {{", kMaxNesting);
      dots = 0;
    } else if (ch == ']' || ch == '}') {
      depth = std::max(0, depth - 1);
      dots = 0;
    } else if (ch == '.') {
      if (++dots >= kMaxKeyComponents)
        return where(i) + fmt::format(": a dotted key of more than {} components", kMaxKeyComponents);
    } else if (ch == '=' || ch == ',') {
      dots = 0;
    }
  }
  return {};
}

enum class Kind { kNumber, kInteger, kString, kBoolean, kNumberArray, kMatrix, kTable, kTableArray };

// Every key a scene may hold (docs/scenes.md lists each with its default and constraint).
const std::map<std::string, Kind>& Schema() {
  static const std::map<std::string, Kind> schema = {
      {"title", Kind::kString},
      {"structure", Kind::kTable},
      {"structure.frequencies", Kind::kNumberArray},
      {"structure.forcing", Kind::kNumberArray},
      {"structure.contact", Kind::kNumberArray},
      {"structure.damping_ratios", Kind::kNumberArray},
      {"structure.mass", Kind::kMatrix},
      {"structure.stiffness", Kind::kMatrix},
      {"structure.forcing_dof", Kind::kInteger},
      {"structure.contact_dof", Kind::kInteger},
      {"structure.modes", Kind::kInteger},
      {"stop", Kind::kTable},
      {"stop.position", Kind::kNumber},
      {"stop.restitution", Kind::kNumber},
      {"stop.stiffness", Kind::kNumber},
      {"stop.damping", Kind::kNumber},
      {"stop.separation", Kind::kString},
      {"contact", Kind::kTableArray},
      {"contact.dof", Kind::kInteger},
      {"contact.dofs", Kind::kNumberArray},
      {"contact.modal", Kind::kNumberArray},
      {"contact.side", Kind::kString},
      {"contact.position", Kind::kNumber},
      {"contact.restitution", Kind::kNumber},
      {"contact.stiffness", Kind::kNumber},
      {"contact.damping", Kind::kNumber},
      {"contact.separation", Kind::kString},
      {"excitation", Kind::kTable},
      {"excitation.amplitude", Kind::kNumber},
      {"excitation.frequency", Kind::kNumber},
      {"excitation.phase", Kind::kNumber},
      {"excitation.vectors", Kind::kMatrix},
      {"initial", Kind::kTable},
      {"initial.time", Kind::kNumber},
      {"initial.displacement", Kind::kNumberArray},
      {"initial.velocity", Kind::kNumberArray},
      {"run", Kind::kTable},
      {"run.periods", Kind::kInteger},
      {"run.engine", Kind::kString},
      {"run.rtol", Kind::kNumber},
      {"run.atol", Kind::kNumber},
      {"run.method", Kind::kString},
      {"run.max_step", Kind::kNumber},
      {"run.max_steps", Kind::kInteger},
      {"run.chatter", Kind::kString},
      {"run.chatter_switch", Kind::kNumber},
      {"run.chatter_tolerance", Kind::kNumber},
      {"run.precision", Kind::kString},
      {"run.samples_per_period", Kind::kInteger},
      {"run.max_period", Kind::kInteger},
      {"run.period_tolerance", Kind::kNumber},
      {"run.lyapunov", Kind::kBoolean},
  };
  return schema;
}

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string LastComponent(const std::string& path) {
  const auto dot = path.rfind('.');
  return dot == std::string::npos ? path : path.substr(dot + 1);
}

// The closest known key: same table first, then any table (a key put in the wrong section).
std::string Suggest(const std::string& path) {
  const std::string leaf = LastComponent(path);
  std::string best;
  size_t best_d = std::max<size_t>(2, path.size() / 3) + 1, best_full = 0;
  for (const auto& [known, kind] : Schema()) {
    (void)kind;
    const size_t full = EditDistance(path, known);
    size_t d = std::min(full, EditDistance(leaf, LastComponent(known)) + 1);
    // A shortened key of the same table (`structure.damping` for `structure.damping_ratios`) is the
    // nearest miss: nearer than the same leaf in another table (`stop.damping`, a compliant stop's).
    const std::string known_leaf = LastComponent(known);
    if (leaf.size() >= 4 && known_leaf.rfind(leaf, 0) == 0 &&
        path.substr(0, path.size() - leaf.size()) == known.substr(0, known.size() - known_leaf.size()))
      d = 0;
    // Ties (the same leaf in two tables: stop.restitution, contact.restitution) go to the
    // closer whole key.
    if (d < best_d || (d == best_d && !best.empty() && full < best_full)) {
      best_d = d;
      best_full = full;
      best = known;
    }
  }
  return best;
}

class Reader {
 public:
  Reader(toml::table root, std::string source) : root_(std::move(root)), source_(std::move(source)) {}

  std::vector<std::string>& messages() { return messages_; }
  const toml::table& root() const { return root_; }
  toml::table& mutable_root() { return root_; }

  std::string Where(const toml::node* n) const {
    if (n == nullptr) return source_;
    return Where(n->source(), n);
  }
  std::string Where(const toml::source_region& src, const toml::node* n) const {
    if (src.begin.line == 0 && n != nullptr && &src != &n->source()) return Where(n);
    const std::string path = src.path ? *src.path : source_;
    if (path.rfind("--set", 0) == 0) return path;
    if (src.begin.line == 0) return path;
    return fmt::format("{}:{}:{}", path, src.begin.line, src.begin.column);
  }
  // The value as the user wrote it, not toml++'s 17 digits: 2.3, never 2.2999999999999998.
  static std::string Show(const toml::node& n) {
    std::ostringstream os;
    bool text = false;
    n.visit([&os, &text](const auto& concrete) {
      if constexpr (toml::is_string<decltype(concrete)>) {
        os << '"' << concrete.get() << '"';
        text = true;
      } else {
        os << concrete;
      }
    });
    // On one line: toml++ writes a nested array over several lines; a newline and its indent go
    // (a space after a comma).
    const std::string written = os.str();
    if (text) return written;  // a string as written (the CLI shows a newline in it escaped)
    std::string out;
    for (size_t i = 0; i < written.size(); ++i) {
      if (written[i] != '\n') {
        out += written[i];
        continue;
      }
      while (i + 1 < written.size() && (written[i + 1] == ' ' || written[i + 1] == '\t')) ++i;
      if (!out.empty() && out.back() == ',') out += ' ';
    }
    return ShortestFloats(out);
  }
  void Report(const toml::node* n, const std::string& key, const std::string& what) {
    reported_.push_back(key);
    if (n)
      messages_.push_back(fmt::format("{}: {} = {}: {}", Where(n), key, Show(*n), what));
    else
      messages_.push_back(fmt::format("{}: {}: {}", source_, key, what));
  }

  // Unknown keys and wrong kinds, for the whole tree.
  void CheckKeys(const toml::table& t, const std::string& prefix) {
    for (const auto& [k, node] : t) {
      const std::string path = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
      const auto it = Schema().find(path);
      if (it == Schema().end()) {
        const std::string hint = Suggest(path);
        messages_.push_back(fmt::format("{}: {}: unknown key{}", Where(k.source(), &node), path,
                                        hint.empty() ? "" : "; did you mean " + hint + "?"));
        continue;
      }
      if (it->second == Kind::kTable) {
        if (const auto* sub = node.as_table())
          CheckKeys(*sub, path);
        else
          Report(&node, path, "expected a table [" + path + "]");
      }
      if (it->second == Kind::kTableArray) {
        const auto* arr = node.as_array();
        bool tables = arr != nullptr && !arr->empty();
        if (arr)
          for (const auto& e : *arr) tables = tables && e.is_table();
        if (!tables) {
          Report(&node, path, "expected an array of tables [[" + path + "]]");
          continue;
        }
        for (const auto& e : *arr) CheckKeys(*e.as_table(), path);
      }
    }
  }

  const toml::node* Find(const std::string& path) const {
    return root_.at_path(path).node();
  }

  std::optional<double> Number(const std::string& path) {
    const toml::node* n = Find(path);
    if (!n) return std::nullopt;
    double v;
    if (const auto* i = n->as_integer())
      v = static_cast<double>(i->get());
    else if (const auto* f = n->as_floating_point())
      v = f->get();
    else {
      Report(n, path, "expected a number");
      return std::nullopt;
    }
    if (!std::isfinite(v)) {
      Report(n, path, "a finite number (no nan or inf)");
      return std::nullopt;
    }
    return v;
  }

  // A whole number in [lo, hi], checked before any conversion to a narrower type.
  std::optional<long long> Integer(const std::string& path, long long lo, long long hi) {
    const toml::node* n = Find(path);
    if (!n) return std::nullopt;
    std::optional<long long> v;
    if (const auto* i = n->as_integer()) v = i->get();
    if (const auto* f = n->as_floating_point()) {
      const double d = f->get();
      if (std::isfinite(d) && d == std::floor(d) && std::abs(d) < 9e15) v = static_cast<long long>(d);
    }
    if (!v) {
      Report(n, path, "expected a whole number");
      return std::nullopt;
    }
    if (*v < lo) {
      Report(n, path, fmt::format("violated constraint {} ≥ {}", LastComponent(path), lo));
      return std::nullopt;
    }
    if (*v > hi) {
      Report(n, path, fmt::format("violated constraint {} ≤ {}", LastComponent(path), hi));
      return std::nullopt;
    }
    return v;
  }

  std::optional<std::string> String(const std::string& path,
                                    const std::vector<std::string>& allowed = {}) {
    const toml::node* n = Find(path);
    if (!n) return std::nullopt;
    const auto* s = n->as_string();
    if (!s) {
      Report(n, path, "expected a string");
      return std::nullopt;
    }
    if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), s->get()) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : " | ") + ("\"" + a + "\"");
      Report(n, path, "one of " + list);
      return std::nullopt;
    }
    return s->get();
  }

  std::optional<bool> Boolean(const std::string& path) {
    const toml::node* n = Find(path);
    if (!n) return std::nullopt;
    const auto* b = n->as_boolean();
    if (!b) {
      Report(n, path, "expected true or false");
      return std::nullopt;
    }
    return b->get();
  }

  // Numbers of an array node; reports and returns nullopt on any bad element.
  std::optional<Eigen::VectorXd> ArrayOf(const toml::node* n, const std::string& path) {
    const auto* a = n->as_array();
    if (!a) {
      Report(n, path, "expected an array of numbers");
      return std::nullopt;
    }
    Eigen::VectorXd v(static_cast<Eigen::Index>(a->size()));
    for (size_t i = 0; i < a->size(); ++i) {
      const toml::node& e = *a->get(i);
      double x;
      if (const auto* in = e.as_integer())
        x = static_cast<double>(in->get());
      else if (const auto* fl = e.as_floating_point())
        x = fl->get();
      else {
        Report(n, path, fmt::format("expected an array of numbers (element {} is not)", i));
        return std::nullopt;
      }
      if (!std::isfinite(x)) {
        Report(n, path, fmt::format("finite numbers only (element {} is {})", i, x));
        return std::nullopt;
      }
      v[static_cast<Eigen::Index>(i)] = x;
    }
    return v;
  }

  std::optional<Eigen::VectorXd> Vector(const std::string& path) {
    const toml::node* n = Find(path);
    if (!n) return std::nullopt;
    return ArrayOf(n, path);
  }

  std::optional<Eigen::MatrixXd> Matrix(const std::string& path) {
    const toml::node* n = Find(path);
    if (!n) return std::nullopt;
    const auto* a = n->as_array();
    if (!a || a->empty()) {
      Report(n, path, "expected a non-empty array of rows (arrays of numbers)");
      return std::nullopt;
    }
    std::vector<Eigen::VectorXd> rows;
    for (size_t i = 0; i < a->size(); ++i) {
      const toml::node* row = a->get(i);
      if (!row->as_array()) {
        Report(n, path, fmt::format("expected an array of rows (row {} is not an array)", i));
        return std::nullopt;
      }
      auto r = ArrayOf(row, path);
      if (!r) return std::nullopt;
      // An empty row is no row of numbers: `vectors = [[]]` was taken for no forcing vector.
      if (r->size() == 0) {
        Report(n, path, fmt::format("rows of at least one number (row {} is empty)", i));
        return std::nullopt;
      }
      if (!rows.empty() && r->size() != rows.front().size()) {
        Report(n, path, fmt::format("rows of equal length (row 0 has {}, row {} has {})",
                                    rows.front().size(), i, r->size()));
        return std::nullopt;
      }
      rows.push_back(*r);
    }
    Eigen::MatrixXd m(static_cast<Eigen::Index>(rows.size()), rows.front().size());
    for (size_t i = 0; i < rows.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = rows[i].transpose();
    return m;
  }

  void Require(const std::string& path) {
    if (!Find(path)) {
      reported_.push_back(path);  // the physics check of a missing key says nothing more
      const auto dot = path.rfind('.');
      const toml::node* table = dot == std::string::npos ? nullptr : Find(path.substr(0, dot));
      messages_.push_back(fmt::format("{}: {}: missing required key", Where(table), path));
    }
  }

 private:
  toml::table root_;
  std::string source_;
  std::vector<std::string> messages_;
  std::vector<std::string> reported_;  // keys with a message already

 public:
  bool Reported(const std::string& key) const {
    return std::find(reported_.begin(), reported_.end(), key) != reported_.end();
  }
};

// A key of one table of an array of tables, KEY[i].LEAF or KEY[i].LEAF[k] (the [[contact]]
// tables: contact[1].position, contact[1].modal[0]). `valid` is false when the text has the shape
// but not a whole index ≥ 0 (the message says what is expected).
struct TableArrayKey {
  std::string base, leaf;  // "contact", "position"
  size_t index = 0;        // i
  std::optional<size_t> entry;  // k of LEAF[k]
  bool valid = true;
};

std::optional<TableArrayKey> ParseTableArrayKey(const std::string& key) {
  const auto bracket = key.find('[');
  if (bracket == std::string::npos) return std::nullopt;
  const auto it = Schema().find(key.substr(0, bracket));
  if (it == Schema().end() || it->second != Kind::kTableArray) return std::nullopt;
  TableArrayKey k;
  k.base = it->first;
  const auto whole = [](const std::string& s, size_t& out) {
    if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos) return false;
    out = static_cast<size_t>(std::stoul(s));
    return true;
  };
  const auto close = key.find(']', bracket);
  if (close == std::string::npos || !whole(key.substr(bracket + 1, close - bracket - 1), k.index) ||
      close + 1 >= key.size() || key[close + 1] != '.') {
    k.valid = false;
    return k;
  }
  std::string rest = key.substr(close + 2);
  if (const auto open = rest.find('['); open != std::string::npos) {
    size_t e = 0;
    if (rest.back() != ']' || !whole(rest.substr(open + 1, rest.size() - open - 2), e)) {
      k.valid = false;
      return k;
    }
    k.entry = e;
    rest.resize(open);
  }
  k.leaf = rest;
  k.valid = !rest.empty();
  return k;
}

// The compliant-stop keys of the table at `at` ("stop" or "contact[j]", docs/compliant.md):
// stiffness k > 0 makes the stop compliant; damping c ≥ 0 and separation = "force" | "gap" belong
// to a compliant stop only, and restitution to a rigid one only (a compliant stop's restitution
// follows from its damping and rule).
Compliance ReadCompliance(Reader& rd, const std::string& at) {
  Compliance c;
  const toml::node* k = rd.Find(at + ".stiffness");
  if (auto v = rd.Number(at + ".stiffness")) {
    if (!(*v > 0))
      rd.Report(k, at + ".stiffness",
                "k > 0 (a compliant stop's stiffness; omit stiffness for a rigid stop)");
    else
      c.stiffness = *v;
  }
  if (auto v = rd.Number(at + ".damping")) {
    if (!(*v >= 0)) rd.Report(rd.Find(at + ".damping"), at + ".damping", "c ≥ 0 (a compliant stop's damping)");
    else c.damping = *v;
  }
  if (auto v = rd.String(at + ".separation", {"force", "gap"}))
    c.separation = *v == "gap" ? Separation::kGap : Separation::kForce;
  if (!k) {
    for (const char* leaf : {"damping", "separation"})
      if (const toml::node* n = rd.Find(at + "." + leaf))
        rd.Report(n, at + "." + leaf,
                  "belongs to a compliant stop: give its stiffness too (a stop without stiffness is rigid "
                  "and takes restitution)");
  } else if (const toml::node* n = rd.Find(at + ".restitution")) {
    rd.Report(n, at + ".restitution",
              "a compliant stop (stiffness given) has no restitution key: its restitution follows from "
              "its damping and separation rule (docs/compliant.md); give restitution only for a rigid stop");
  }
  return c;
}

// How many contacts the scene table `root` has: its [[contact]] tables, or 1 for a [stop].
size_t ContactCount(const toml::table& root) {
  if (const auto* a = root.get_as<toml::array>("contact")) return a->size();
  return root.get_as<toml::table>("stop") ? 1 : 0;
}

// Why the scene table `root` has no contact `k.index` ("" when it has): the key and how many
// contacts there are.
std::string MissingContact(const toml::table& root, const TableArrayKey& k, const std::string& key) {
  const size_t m = ContactCount(root);
  if (k.index < m) return {};
  const std::string which = m == 0   ? "none"
                            : root.get_as<toml::array>("contact")
                                ? (m == 1 ? "contact[0], its one [[contact]] table"
                                          : fmt::format("contact[0] to contact[{}], its [[contact]] tables", m - 1))
                                : "contact[0], its [stop] table";
  return fmt::format("{}: no contact {}: the scene has {} contact{} ({}); expected an index in [0, {})", key,
                     k.index, m, m == 1 ? "" : "s", which, m);
}

// Applies `value` at KEY[i].LEAF (ApplyOverride): the [stop] of a one-contact scene is contact[0]
// (position and restitution); an index beyond the scene's contacts is refused with their count.
void ApplyTableArrayOverride(toml::table& root, const TableArrayKey& k, const std::string& key,
                             const std::string& where, toml::node& value, std::vector<std::string>& messages) {
  if (!k.valid) {
    messages.push_back(fmt::format("{}: {}: expected {}[i].KEY or {}[i].KEY[j] with indices ≥ 0 (e.g. "
                                   "{}[1].position=0.5)",
                                   where, key, k.base, k.base, k.base));
    return;
  }
  const std::string schema_key = k.base + "." + k.leaf;
  const auto known = Schema().find(schema_key);
  if (known == Schema().end()) {
    const std::string hint = Suggest(schema_key);
    const bool same_table = hint.rfind(k.base + ".", 0) == 0;
    messages.push_back(fmt::format(
        "{}: {}: unknown key{}", where, key,
        hint.empty() ? ""
                     : "; did you mean " +
                           (same_table ? fmt::format("{}[{}].{}", k.base, k.index, hint.substr(k.base.size() + 1))
                                       : hint) +
                           "?"));
    return;
  }
  if (const std::string missing = MissingContact(root, k, key); !missing.empty()) {
    messages.push_back(fmt::format("{}: {}", where, missing));
    return;
  }
  toml::table* table = nullptr;
  if (auto* a = root.get_as<toml::array>("contact")) {
    table = a->get(k.index) ? a->get(k.index)->as_table() : nullptr;
  } else {  // the [stop] shorthand: contact[0]
    if (k.leaf != "position" && k.leaf != "restitution" && k.leaf != "stiffness" && k.leaf != "damping" &&
        k.leaf != "separation") {
      messages.push_back(fmt::format("{}: {}: the scene's one contact is its [stop] table, which takes position, "
                                     "restitution, stiffness, damping and separation (give [[contact]] tables for more)",
                                     where, key));
      return;
    }
    table = root.get_as<toml::table>("stop");
  }
  if (!table) {
    messages.push_back(fmt::format("{}: {}: {}[{}] is not a table", where, key, k.base, k.index));
    return;
  }
  if (k.entry) {
    auto* arr = table->get_as<toml::array>(k.leaf);
    if (!(value.is_integer() || value.is_floating_point())) {
      messages.push_back(fmt::format("{}: {}: an entry of an array takes a number", where, key));
      return;
    }
    if (!arr || *k.entry >= arr->size()) {
      messages.push_back(fmt::format("{}: {}: the scene has no such entry ({}[{}].{} {}; give the whole array "
                                     "with --set {}[{}].{}=[...])",
                                     where, key, k.base, k.index, k.leaf,
                                     arr               ? fmt::format("has {} entries", arr->size())
                                     : table->get(k.leaf) ? std::string("is not an array")
                                                          : std::string("is not given"),
                                     k.base, k.index, k.leaf));
      return;
    }
    arr->replace(arr->cbegin() + static_cast<std::ptrdiff_t>(*k.entry), value.value<double>().value_or(0.0));
    return;
  }
  table->insert_or_assign(k.leaf, std::move(value));
}

// Applies one `KEY=VALUE` override to the table (VALUE in TOML syntax, e.g. 2.5, "exact", [1, 2]).
void ApplyOverride(toml::table& root, const std::string& text, std::vector<std::string>& messages) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    messages.push_back(fmt::format("--set {}: expected KEY=VALUE (e.g. excitation.amplitude=2.5)", text));
    return;
  }
  std::string key = text.substr(0, eq);
  std::string value = text.substr(eq + 1);
  key.erase(key.find_last_not_of(" \t") + 1);
  key.erase(0, key.find_first_not_of(" \t"));
  const std::string where = "--set " + text;
  // KEY[i] / KEY[i][j] (below) name an entry of the array KEY.
  if (Schema().find(key.substr(0, key.find('['))) == Schema().end()) {
    const std::string hint = Suggest(key.substr(0, 200));
    messages.push_back(fmt::format("{}: {}: unknown key{}", where.substr(0, 300), key.substr(0, 200),
                                   hint.empty() ? "" : "; did you mean " + hint + "?"));
    return;
  }
  if (const auto problem = PreScan(value, where); !problem.empty()) {
    messages.push_back(problem);
    return;
  }
  toml::table parsed;
  try {
    parsed = toml::parse("value = " + value, where);
  } catch (const toml::parse_error& e) {
    messages.push_back(fmt::format("{}: {}: VALUE is not valid TOML ({}); strings need quotes, "
                                   "e.g. run.engine='\"exact\"'",
                                   where, key, e.description()));
    return;
  }
  if (parsed.size() != 1 || !parsed.get("value")) {
    messages.push_back(fmt::format("{}: {}: VALUE must be one TOML value, not more TOML (e.g. "
                                   "excitation.amplitude=2.5)",
                                   where, key));
    return;
  }
  if (const auto k = ParseTableArrayKey(key)) {
    ApplyTableArrayOverride(root, *k, key, where, *parsed.get("value"), messages);
    return;
  }
  // KEY[i] or KEY[i][j]: one entry of an array or matrix of the scene (continuation of modal data,
  // damping ratios, matrix entries). The matrices are symmetric: [i][j] also sets [j][i].
  std::vector<size_t> index;
  if (const auto bracket = key.find('['); bracket != std::string::npos) {
    std::string rest = key.substr(bracket);
    key.resize(bracket);
    while (!rest.empty()) {
      const auto close = rest.find(']');
      size_t used = 0;
      long long i = -1;
      try {
        if (rest[0] == '[' && close != std::string::npos) i = std::stoll(rest.substr(1, close - 1), &used);
      } catch (const std::exception&) {
        i = -1;
      }
      if (i < 0 || used != close - 1) {
        messages.push_back(fmt::format("{}: {}{}: expected KEY[i] or KEY[i][j] with indices ≥ 0", where, key, rest));
        return;
      }
      index.push_back(static_cast<size_t>(i));
      rest.erase(0, close + 1);
    }
  }
  if (!index.empty() && Schema().find(key) != Schema().end()) {
    const auto* node = root.at_path(key).node();
    const toml::array* arr = node ? node->as_array() : nullptr;
    const auto* v = parsed.get("value");
    if (!v || !(v->is_integer() || v->is_floating_point())) {
      messages.push_back(fmt::format("{}: {}: an entry of an array takes a number", where, key));
      return;
    }
    const double x = v->value<double>().value_or(0.0);
    const auto entry = [&](size_t i, size_t j) -> toml::node* {
      auto* a = root.at_path(key).as_array();
      if (!a || i >= a->size()) return nullptr;
      if (index.size() == 1) return a->get(i);
      auto* row = a->get(i) ? a->get(i)->as_array() : nullptr;
      return row && j < row->size() ? row->get(j) : nullptr;
    };
    const size_t i = index[0], j = index.size() > 1 ? index[1] : 0;
    if (!arr || index.size() > 2 || !entry(i, j) || (index.size() == 2 && !entry(j, i))) {
      messages.push_back(fmt::format("{}: {}: the scene has no such entry (give the whole array in the "
                                     "scene or with --set {}=[...])",
                                     where, text.substr(0, eq), key));
      return;
    }
    const auto set = [&](size_t a, size_t b) {
      auto* base = root.at_path(key).as_array();
      if (index.size() == 1)
        base->replace(base->cbegin() + static_cast<std::ptrdiff_t>(a), x);
      else {
        auto* row = base->get(a)->as_array();
        row->replace(row->cbegin() + static_cast<std::ptrdiff_t>(b), x);
      }
    };
    set(i, j);
    if (index.size() == 2) set(j, i);
    return;
  }
  if (Schema().find(key) == Schema().end()) {
    const std::string hint = Suggest(key);
    messages.push_back(fmt::format("{}: {}: unknown key{}", where, key,
                                   hint.empty() ? "" : "; did you mean " + hint + "?"));
    return;
  }
  toml::table* table = &root;
  size_t start = 0;
  for (size_t dot = key.find('.'); dot != std::string::npos; dot = key.find('.', start)) {
    const std::string part = key.substr(start, dot - start);
    auto* sub = table->get(part);
    if (!sub) sub = table->insert_or_assign(part, toml::table{}).first->second.as_table();
    if (!sub || !sub->as_table()) {
      messages.push_back(fmt::format("{}: {}: {} is not a table", where, key, part));
      return;
    }
    table = sub->as_table();
    start = dot + 1;
  }
  table->insert_or_assign(key.substr(start), std::move(*parsed.get("value")));
}

// The length of the float token [-+]?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)? that starts at text[i]
// (0: none, the longest match as a regular expression would take it), and whether it has a
// fraction or an exponent (an integer is not rewritten). Scanned by hand: compiling the
// equivalent std::regex cost every process that reads a scene about 1.9 M instructions, an eighth
// of a whole 20-period run of Fig. 8 (docs/performance.md, "Start-up").
size_t FloatToken(const std::string& text, size_t i, bool& fraction_or_exponent) {
  const auto digit = [&](size_t k) { return k < text.size() && std::isdigit(static_cast<unsigned char>(text[k])); };
  size_t j = i;
  if (j < text.size() && (text[j] == '-' || text[j] == '+')) ++j;
  const size_t first_digit = j;
  while (digit(j)) ++j;
  fraction_or_exponent = false;
  if (j == first_digit) return 0;
  if (j < text.size() && text[j] == '.' && digit(j + 1)) {
    j += 2;
    while (digit(j)) ++j;
    fraction_or_exponent = true;
  }
  if (j < text.size() && (text[j] == 'e' || text[j] == 'E')) {
    size_t k = j + 1;
    if (k < text.size() && (text[k] == '-' || text[k] == '+')) ++k;
    if (digit(k)) {
      while (digit(k)) ++k;
      j = k;
      fraction_or_exponent = true;
    }
  }
  return j - i;
}

// toml++ writes every float with 17 significant digits (2.8 → 2.7999999999999998): rewrite each
// float token outside strings in its shortest round-trip form, kept a TOML float.
std::string ShortestFloats(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '"' || c == '\'') {  // a string, copied as it is (escapes included)
      size_t j = i + 1;
      while (j < text.size() && text[j] != c) j += (text[j] == '\\' && c == '"') ? 2 : 1;
      j = std::min(j + 1, text.size());
      out.append(text, i, j - i);
      i = j;
      continue;
    }
    const bool starts = (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+') &&
                        (i == 0 || !(std::isalnum(static_cast<unsigned char>(text[i - 1])) ||
                                     text[i - 1] == '_' || text[i - 1] == '.' || text[i - 1] == ':'));
    bool fraction_or_exponent = false;
    const size_t length = starts ? FloatToken(text, i, fraction_or_exponent) : 0;
    if (length > 0 && fraction_or_exponent) {
      const size_t end = i + length;
      const bool word_follows = end < text.size() && (std::isalnum(static_cast<unsigned char>(text[end])) ||
                                                      text[end] == '_' || text[end] == '-' || text[end] == ':');
      if (!word_follows) {  // not a date, a time or part of a bare key
        // strtod, not stod: a subnormal or overflowing token is kept as written, never thrown on.
        const std::string token = text.substr(i, length);
        const double value = std::strtod(token.c_str(), nullptr);
        std::string shortest = std::isfinite(value) && value != 0.0 ? fmt::format("{}", value) : token;
        if (shortest.find_first_of(".eEni") == std::string::npos) shortest += ".0";
        out += shortest;
        i = end;
        continue;
      }
    }
    out += c;
    ++i;
  }
  return out;
}

// [excitation]: a number each (f sin ωt, today's forcing) or lists of one length, one entry per
// harmonic, with an optional phase and forcing vectors (docs/harmonics.md). Lists, a phase or
// vectors make the scene's `harmonics`; its amplitude and frequency are then f_0 and the base
// pulsation of the common period.
void ReadExcitation(Reader& rd, Scene& s) {
  struct Entry {
    const char* key;
    std::optional<Eigen::VectorXd> values;
    bool list = false;
  };
  std::array<Entry, 3> e{{{"excitation.amplitude", {}}, {"excitation.frequency", {}}, {"excitation.phase", {}}}};
  bool bad = false;
  for (Entry& x : e) {
    const toml::node* n = rd.Find(x.key);
    if (!n) continue;
    if (n->is_array()) {
      x.list = true;
      x.values = rd.ArrayOf(n, x.key);
      if (x.values && x.values->size() == 0) {
        rd.Report(n, x.key, "a non-empty list, one entry per harmonic");
        x.values.reset();
      }
    } else if (auto v = rd.Number(x.key)) {
      x.values = Eigen::VectorXd::Constant(1, *v);
    }
    if (!x.values) bad = true;
  }
  std::optional<Eigen::MatrixXd> vectors;
  if (rd.Find("excitation.vectors")) {
    vectors = rd.Matrix("excitation.vectors");
    if (!vectors) bad = true;
  }
  const bool lists = e[0].list || e[1].list || e[2].list;
  if (!lists) {  // numbers: harmonic 0 alone
    if (e[0].values) s.amplitude = (*e[0].values)[0];
    if (e[1].values) s.frequency = (*e[1].values)[0];
  }
  if (bad || !e[0].values || !e[1].values) return;
  const bool phase = e[2].values.has_value();
  if (!lists && !phase && !vectors) return;
  // Every list of one length; a number beside a list is refused (which harmonic would it be?).
  const Eigen::Index H = lists ? std::max({e[0].list ? e[0].values->size() : 0, e[1].list ? e[1].values->size() : 0,
                                           e[2].list && phase ? e[2].values->size() : 0})
                               : 1;
  for (const Entry& x : e) {
    if (!x.values) continue;
    if (lists && !x.list) {
      rd.Report(rd.Find(x.key), x.key,
                fmt::format("a list of {} (one per harmonic), as the other [excitation] lists", H));
      bad = true;
    } else if (x.values->size() != H) {
      rd.Report(rd.Find(x.key), x.key,
                fmt::format("one entry per harmonic: {} expected (the longest [excitation] list), got {}", H,
                            x.values->size()));
      bad = true;
    }
  }
  if (vectors && vectors->rows() != H) {
    rd.Report(rd.Find("excitation.vectors"), "excitation.vectors",
              fmt::format("one forcing vector (row) per harmonic: {} rows expected, got {}", H, vectors->rows()));
    bad = true;
  }
  if (bad) return;
  s.harmonics.resize(static_cast<size_t>(H));
  for (Eigen::Index h = 0; h < H; ++h) {
    HarmonicSpec& hs = s.harmonics[static_cast<size_t>(h)];
    hs.amplitude = (*e[0].values)[h];
    hs.frequency = (*e[1].values)[h];
    hs.phase = phase ? (*e[2].values)[h] : 0.0;
    if (vectors) hs.vector = vectors->row(h).transpose();
  }
  s.amplitude = s.harmonics[0].amplitude;
  std::vector<double> w;
  for (const HarmonicSpec& hs : s.harmonics) w.push_back(hs.frequency);
  const CommonPeriod cp = FindCommonPeriod(w);
  s.frequency = cp.commensurate ? cp.base : s.harmonics[0].frequency;
}

LoadedScene Build(toml::table root, const std::string& source,
                  const std::vector<std::string>& overrides) {
  std::vector<std::string> messages;
  for (const auto& o : overrides) ApplyOverride(root, o, messages);

  Reader rd(std::move(root), source);
  for (auto& m : messages) rd.messages().push_back(m);
  rd.CheckKeys(rd.root(), "");

  Scene s;
  if (auto t = rd.String("title")) s.title = *t;

  // Structure: the form is decided by which keys are present.
  const bool modal_keys = rd.Find("structure.frequencies") || rd.Find("structure.forcing") ||
                          rd.Find("structure.contact");
  const bool physical_keys = rd.Find("structure.mass") || rd.Find("structure.stiffness") ||
                             rd.Find("structure.forcing_dof") || rd.Find("structure.contact_dof");
  if (!rd.Find("structure")) {
    rd.messages().push_back(fmt::format(
        "{}: structure: missing required table [structure] (modal form: frequencies, forcing, "
        "contact; or physical form: mass, stiffness, forcing_dof, contact_dof)",
        source));
  } else if (modal_keys && physical_keys) {
    rd.Report(rd.Find("structure"), "structure",
              "give either the modal form (frequencies, forcing, contact) or the physical form "
              "(mass, stiffness, forcing_dof, contact_dof), not both");
  } else if (physical_keys) {
    for (const char* k : {"structure.mass", "structure.stiffness", "structure.forcing_dof"})
      rd.Require(k);
    if (!rd.Find("contact")) rd.Require("structure.contact_dof");
    PhysicalStructureSpec p;
    auto M = rd.Matrix("structure.mass");
    auto K = rd.Matrix("structure.stiffness");
    auto a = rd.Integer("structure.forcing_dof", -kMaxIndex, kMaxIndex);
    auto b = rd.Find("contact") ? std::optional<long long>(0)
                                : rd.Integer("structure.contact_dof", -kMaxIndex, kMaxIndex);
    if (M && K && a && b) {
      p.mass = *M;
      p.stiffness = *K;
      p.forcing_dof = static_cast<int>(*a);
      p.contact_dof = static_cast<int>(*b);
      s.physical = p;
    }
  } else {
    for (const char* k : {"structure.frequencies", "structure.forcing", "structure.contact"})
      rd.Require(k);
    auto w = rd.Vector("structure.frequencies");
    auto ta = rd.Vector("structure.forcing");
    auto tb = rd.Vector("structure.contact");
    if (w && ta && tb) s.modal = ModalStructureSpec{*w, *ta, *tb};
  }
  if (auto z = rd.Vector("structure.damping_ratios")) s.damping_ratios = *z;
  if (auto m = rd.Integer("structure.modes", std::numeric_limits<long long>::min(), kMaxIndex)) {
    if (*m < 1)
      rd.Report(rd.Find("structure.modes"), "structure.modes", "modes ≥ 1 (omit it to keep all)");
    else
      s.modes = static_cast<int>(*m);
  }

  // One contact ([stop], the shorthand) or several ([[contact]] tables), never both.
  const toml::array* contact_tables = rd.Find("contact") ? rd.Find("contact")->as_array() : nullptr;
  if (contact_tables && rd.Find("stop")) {
    rd.Report(rd.Find("stop"), "stop",
              "give either [stop] (one contact) or [[contact]] tables, not both");
  } else if (contact_tables) {
    if (s.physical && rd.Find("structure.contact_dof"))
      rd.Report(rd.Find("structure.contact_dof"), "structure.contact_dof",
                "belongs to the [stop] shorthand: with [[contact]] tables each contact names its DOF");
    for (size_t j = 0; j < contact_tables->size() && contact_tables->get(j)->is_table(); ++j) {
      const std::string at = fmt::format("contact[{}]", j);
      ContactSpec k;
      const bool one = rd.Find(at + ".dof") != nullptr, two = rd.Find(at + ".dofs") != nullptr;
      if (s.modal) {
        // The modal form names no DOF: a contact reads the modes through `modal`, except contact 0,
        // the contact of the scaling (docs/contacts.md, "the modal form").
        for (const char* leaf : {"dof", "dofs"})
          if (const toml::node* n = rd.Find(at + "." + leaf))
            rd.Report(n, at + "." + leaf,
                      "the modal form names no DOF: give the contact's modal components, modal = "
                      "[a_1, …, a_n] (docs/contacts.md)");
        if (j == 0 && rd.Find(at + ".modal"))
          rd.Report(rd.Find(at + ".modal"), at + ".modal",
                    "contact 0 is the contact of the modal scaling: its components are fixed "
                    "(a_0,i = +1 below, −1 above, on every mode; structure.contact is its T_B): "
                    "give no modal key for it");
        if (j > 0) {
          rd.Require(at + ".modal");
          if (auto v = rd.Vector(at + ".modal")) k.modal = *v;
        }
        k.dof = -1;
      } else {
        if (const toml::node* n = rd.Find(at + ".modal"))
          rd.Report(n, at + ".modal",
                    "modal components belong to the modal form (frequencies, forcing, contact); in "
                    "the physical form a contact names dof = B or dofs = [B, A]");
        if (one == two)
          rd.messages().push_back(fmt::format(
              "{}: {}: give dof = B (a stop on DOF B) or dofs = [B, A] (an impact pair, the gap on "
              "q_B − q_A), exactly one of them",
              rd.Where(rd.Find(at)), at));
      }
      if (!s.modal)
        if (auto v = rd.Integer(at + ".dof", -kMaxIndex, kMaxIndex)) k.dof = static_cast<int>(*v);
      if (two && !s.modal) {
        const toml::node* n = rd.Find(at + ".dofs");
        const auto* a = n->as_array();
        bool ok = a && a->size() == 2;
        for (size_t i = 0; ok && i < 2; ++i) {
          const auto* in = a->get(i)->as_integer();
          ok = in && in->get() >= -kMaxIndex && in->get() <= kMaxIndex;
        }
        if (!ok) {
          rd.Report(n, at + ".dofs", "two whole numbers [B, A]: the gap is on q_B − q_A");
        } else {
          k.dof = static_cast<int>(a->get(0)->as_integer()->get());
          k.partner = static_cast<int>(a->get(1)->as_integer()->get());
          if (k.partner < 0) k.partner = -2;  // out of range, reported by Validate
        }
      }
      for (const char* leaf : {"side", "position"}) rd.Require(at + "." + leaf);
      k.compliance = ReadCompliance(rd, at);
      if (!rd.Find(at + ".stiffness")) rd.Require(at + ".restitution");
      if (auto v = rd.String(at + ".side", {"below", "above"}))
        k.side = *v == "below" ? Side::kBelow : Side::kAbove;
      if (auto v = rd.Number(at + ".position")) k.position = *v;
      if (auto v = rd.Number(at + ".restitution"); v && !k.compliance.compliant()) k.restitution = *v;
      s.contacts.push_back(k);
    }
    if (s.physical && !s.contacts.empty()) s.physical->contact_dof = s.contacts.front().dof;
  } else {
    rd.Require("stop.position");
    s.stop_compliance = ReadCompliance(rd, "stop");
    if (!rd.Find("stop.stiffness")) rd.Require("stop.restitution");
    if (s.stop_compliance.compliant()) s.restitution = 0;
  }
  if (auto v = rd.Number("stop.position")) s.stop_position = *v;
  if (auto v = rd.Number("stop.restitution"); v && !s.stop_compliance.compliant()) s.restitution = *v;
  rd.Require("excitation.amplitude");
  rd.Require("excitation.frequency");
  ReadExcitation(rd, s);

  if (auto v = rd.Number("initial.time")) s.initial_time = *v;
  if (auto v = rd.Vector("initial.displacement")) s.initial_displacement = *v;
  if (auto v = rd.Vector("initial.velocity")) s.initial_velocity = *v;

  auto& r = s.run;
  if (auto v = rd.Integer("run.periods", 1, 1LL << 53)) r.periods = *v;
  if (auto v = rd.String("run.engine", {"exact", "cvode"}))
    r.engine = *v == "exact" ? Engine::kExact : Engine::kCvode;
  if (auto v = rd.Number("run.rtol")) r.rtol = *v;
  if (auto v = rd.Number("run.atol")) r.atol = *v;
  if (auto v = rd.String("run.method", {"adams", "bdf"}))
    r.method = *v == "adams" ? CvodeMethod::kAdams : CvodeMethod::kBdf;
  if (auto v = rd.Number("run.max_step")) r.max_step = *v;
  if (auto v = rd.Integer("run.max_steps", 1, 1LL << 53)) r.max_steps = static_cast<long>(*v);
  if (auto v = rd.String("run.chatter", {"accumulation", "threshold", "none"}))
    r.chatter = *v == "accumulation" ? ChatterTreatment::kAccumulation
                : *v == "threshold"  ? ChatterTreatment::kThreshold
                                     : ChatterTreatment::kNone;
  if (auto v = rd.Number("run.chatter_switch")) r.chatter_switch = *v;
  if (auto v = rd.Number("run.chatter_tolerance")) r.chatter_tolerance = *v;
  if (auto v = rd.String("run.precision", {"double", "quad"}))
    r.precision = *v == "double" ? Precision::kDouble : Precision::kQuad;
  if (auto v = rd.Integer("run.samples_per_period", 0, 1 << 20)) r.samples_per_period = static_cast<int>(*v);
  if (auto v = rd.Integer("run.max_period", 1, 1 << 12)) r.max_period = static_cast<int>(*v);
  if (auto v = rd.Boolean("run.lyapunov")) r.lyapunov = *v;
  if (auto v = rd.Number("run.period_tolerance")) r.period_tolerance = *v;

  // Physics, once the file gave a structure; keys already reported are not reported twice.
  if (s.modal || s.physical) {
    for (const auto& issue : Validate(s)) {
      if (rd.Reported(issue.key)) continue;
      const toml::node* n = rd.Find(issue.key);
      if (n)
        rd.Report(n, issue.key, "violated constraint " + issue.constraint);
      else
        rd.messages().push_back(fmt::format("{}: {}{}: violated constraint {}", source, issue.key,
                                            issue.value.empty() ? "" : " = " + issue.value,
                                            issue.constraint));
    }
  }
  if (!rd.messages().empty()) throw InputError(rd.messages());

  std::ostringstream text;
  text << rd.root();
  return LoadedScene{std::move(s), source, ShortestFloats(text.str()) + "\n"};
}

}  // namespace

InputError::InputError(std::vector<std::string> messages)
    : std::runtime_error(messages.empty() ? "bad input" : messages.front()),
      messages_(std::move(messages)) {}

LoadedScene ParseScene(std::string_view text, const std::string& source,
                       const std::vector<std::string>& overrides) {
  if (const auto problem = PreScan(text, source); !problem.empty()) throw InputError({problem});
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw InputError({fmt::format("{}:{}:{}: not valid TOML: {}", source, e.source().begin.line,
                                  e.source().begin.column, e.description())});
  }
  return Build(std::move(root), source, overrides);
}

std::string NearestSceneKey(const std::string& key) { return Suggest(key); }

std::optional<double> SceneNumber(const std::string& text, const std::string& key) {
  try {
    const toml::table t = toml::parse(text);
    if (const auto k = ParseTableArrayKey(key); k && k->valid) {
      if (const std::string missing = MissingContact(t, *k, key); !missing.empty()) throw InputError({missing});
      if (!t.get_as<toml::array>(k->base))  // the [stop] shorthand is contact[0]
        return k->entry ? std::nullopt : t.at_path("stop." + k->leaf).value<double>();
    }
    // A sum of harmonics (docs/harmonics.md): excitation.amplitude is f_0, excitation.frequency the
    // base pulsation of the common period.
    if (const auto* list = t.at_path(key).as_array(); list && (key == "excitation.amplitude" || key == "excitation.frequency")) {
      std::vector<double> values;
      for (const auto& e : *list)
        if (auto v = e.value<double>()) values.push_back(*v);
      if (values.empty() || values.size() != list->size()) return std::nullopt;
      if (key == "excitation.amplitude") return values.front();
      for (const double w : values)
        if (!(w > 0) || !std::isfinite(w)) return std::nullopt;
      const CommonPeriod cp = FindCommonPeriod(values);
      return cp.commensurate ? std::optional<double>(cp.base) : std::nullopt;
    }
    return t.at_path(key).value<double>();
  } catch (const toml::parse_error&) {
    return std::nullopt;
  }
}

LoadedScene LoadScene(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError({fmt::format("{}: cannot read the scene file", path)});
  // At most one byte more than a scene may hold (/dev/zero, a FIFO, a huge file end here), read
  // in pieces: a buffer of the largest size, zeroed, would cost every run 1 MiB of fresh pages
  // (a third of a short run's CPU, docs/performance.md "Start-up").
  std::string buffer;
  std::array<char, 16384> piece{};
  while (buffer.size() <= kMaxSceneBytes) {
    in.read(piece.data(), static_cast<std::streamsize>(piece.size()));
    const auto got = static_cast<size_t>(in.gcount());
    buffer.append(piece.data(), std::min(got, kMaxSceneBytes + 1 - buffer.size()));
    if (got < piece.size()) break;
  }
  return ParseScene(buffer, path, overrides);
}

}  // namespace vibro

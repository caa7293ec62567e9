// Contact sequences of periodic orbits (see include/vibro/contact_sequence.hpp).
#include "vibro/contact_sequence.hpp"

#include <algorithm>
#include <compare>
#include <cstdlib>
#include <map>
#include <string_view>

#include <fmt/format.h>

namespace vibro {
namespace {

constexpr const char* kKinds[] = {"impact", "accumulation", "stick", "release", "grazing"};

// A whole number of at most 9 digits, or −1.
long long Whole(const std::string& s) {
  if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::atoll(s.c_str());
}

// KMP failure function of w: fail[i] = length of the longest proper border of w[0, i).
std::vector<size_t> Borders(const std::vector<int>& w) {
  std::vector<size_t> fail(w.size() + 1, 0);
  for (size_t i = 1, k = 0; i < w.size(); ++i) {
    while (k > 0 && w[i] != w[k]) k = fail[k];
    if (w[i] == w[k]) ++k;
    fail[i + 1] = k;
  }
  return fail;
}

// The shortest repeating unit of a cyclic word (w = u^m).
std::vector<int> Primitive(const std::vector<int>& w) {
  if (w.empty()) return w;
  const size_t p = w.size() - Borders(w).back();
  return w.size() % p == 0 ? std::vector<int>(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(p)) : w;
}

// The sequence as tokens, each chattering run one token "j:chattering": a run of impacts at
// contact j that ends in j's accumulation point (absorbed), or directly in j's stick (a simulator
// that ends chattering with a plastic impact below a threshold). The word is read cyclically from
// just after its last accumulation or stick, so that no run wraps around its end; each token
// covers the entries [first, first + size) of `w`, indices modulo w.size().
struct Token {
  std::string name;
  size_t first, size;
};
std::vector<Token> Tokens(const std::vector<std::string>& w) {
  const auto ends = [](const std::string& e, std::string_view tail) {
    return e.size() > tail.size() && e.ends_with(tail);
  };
  const auto last = std::find_if(w.rbegin(), w.rend(), [&](const std::string& e) {
    return ends(e, ":accumulation") || ends(e, ":stick");
  });
  const size_t from = last == w.rend() ? 0 : static_cast<size_t>(w.rend() - last);  // after it
  std::vector<Token> out;
  for (size_t i = 0; i < w.size(); ++i) {
    const size_t at = (from + i) % w.size();
    const std::string& e = w[at];
    const bool acc = ends(e, ":accumulation"), stick = ends(e, ":stick");
    if (!acc && !stick) {
      out.push_back({e, at, 1});
      continue;
    }
    const std::string who = e.substr(0, e.find(':') + 1);  // "j:"
    const std::string impact = who + "impact", chattering = who + "chattering";
    if (stick && !out.empty() && out.back().name == chattering) {  // after its accumulation point
      out.push_back({e, at, 1});
      continue;
    }
    Token run{chattering, at, 0};
    while (!out.empty() && out.back().name == impact) {
      run.first = out.back().first;
      run.size += 1;
      out.pop_back();
    }
    if (acc) run.size += 1;  // the accumulation point ends the run
    if (run.size > 0) out.push_back(run);
    if (stick) out.push_back({e, at, 1});
  }
  return out;
}

// The order of entries and tokens in the canonical rotation: by contacts (their ascending list,
// compared lexicographically: 0 < 0+1 < 1 < 2), then by kind in the order impact, chattering,
// accumulation, stick, release, grazing; an entry not of the form "J:kind" after all others.
struct OrderKey {
  bool malformed;
  std::vector<long long> contacts;
  int kind;
  std::string text;
  auto operator<=>(const OrderKey&) const = default;
};
OrderKey KeyOf(const std::string& e) {
  constexpr const char* kOrder[] = {"impact", "chattering", "accumulation", "stick", "release", "grazing"};
  OrderKey key{false, {}, 0, e};
  const auto colon = e.find(':');
  const auto kind = std::find(std::begin(kOrder), std::end(kOrder), e.substr(colon == std::string::npos ? 0 : colon + 1));
  key.kind = static_cast<int>(kind - std::begin(kOrder));
  for (size_t a = 0; colon != std::string::npos;) {
    const auto plus = e.find('+', a);
    const auto end = plus == std::string::npos || plus > colon ? colon : plus;
    const long long id = Whole(e.substr(a, end - a));
    if (id < 0) break;
    key.contacts.push_back(id);
    if (end == colon) break;
    a = end + 1;
  }
  key.malformed = colon == std::string::npos || key.contacts.empty() || kind == std::end(kOrder);
  return key;
}

// Each word of `words` as integers, equal entries equal integers, in the order of OrderKey.
std::vector<std::vector<int>> Ranked(const std::vector<std::vector<std::string>>& words) {
  std::map<OrderKey, int> rank;
  for (const auto& w : words)
    for (const auto& e : w) rank.emplace(KeyOf(e), 0);
  int next = 0;
  for (auto& [key, r] : rank) r = next++;
  std::vector<std::vector<int>> out;
  for (const auto& w : words) {
    std::vector<int> v;
    v.reserve(w.size());
    for (const auto& e : w) v.push_back(rank.at(KeyOf(e)));
    out.push_back(std::move(v));
  }
  return out;
}

// Where the lexicographically least rotation of a nonempty word starts (the first such start;
// the two-pointer algorithm, O(n)).
template <class T>
size_t LeastRotation(const std::vector<T>& s) {
  const size_t n = s.size();
  size_t i = 0, j = 1, k = 0;
  while (i < n && j < n && k < n) {
    const T& a = s[(i + k) % n];
    const T& b = s[(j + k) % n];
    if (a == b) {
      ++k;
      continue;
    }
    if (b < a)
      i += k + 1;
    else
      j += k + 1;
    if (i == j) ++j;
    k = 0;
  }
  return std::min(i, j);
}

}  // namespace

std::optional<std::vector<std::string>> ParseContactSequence(const std::string& text, int contacts,
                                                             std::string& problem) {
  problem.clear();
  std::vector<std::string> out;
  size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i >= text.size()) break;
    size_t end = i;
    while (end < text.size() && text[end] != ' ' && text[end] != '\t') ++end;
    const std::string entry = text.substr(i, end - i);
    i = end;
    const auto bad = [&](const std::string& why) {
      problem = fmt::format("'{}' is not an event of a contact sequence ({}; expected entries J:KIND or J:KIND*N "
                            "separated by spaces, J a contact index or indices joined by '+', KIND one of impact, "
                            "accumulation, stick, release, grazing, e.g. \"0:impact 1:impact*3 0:stick\")",
                            entry.substr(0, 80), why);
      return std::nullopt;
    };
    const auto colon = entry.find(':');
    if (colon == std::string::npos) return bad("no ':'");
    std::string kind = entry.substr(colon + 1);
    long long count = 1;
    if (const auto star = kind.find('*'); star != std::string::npos) {
      count = Whole(kind.substr(star + 1));
      if (count < 1) return bad("the count after '*' is not a whole number ≥ 1");
      kind.resize(star);
    }
    if (std::find(std::begin(kKinds), std::end(kKinds), kind) == std::end(kKinds)) return bad("unknown event kind");
    std::vector<long long> ids;
    const std::string who = entry.substr(0, colon);
    for (size_t a = 0;;) {
      const auto plus = who.find('+', a);
      const long long id = Whole(who.substr(a, plus == std::string::npos ? std::string::npos : plus - a));
      if (id < 0) return bad("a contact index is not a whole number ≥ 0");
      if (contacts > 0 && id >= contacts)
        return bad(fmt::format("contact {} does not exist: the scene has {} contacts, 0 to {}", id, contacts,
                               contacts - 1));
      ids.push_back(id);
      if (plus == std::string::npos) break;
      a = plus + 1;
    }
    std::sort(ids.begin(), ids.end());
    if (std::adjacent_find(ids.begin(), ids.end()) != ids.end()) return bad("a contact named twice");
    if (ids.size() > 1 && kind != "impact") return bad("only an impact involves several contacts at once");
    if (static_cast<long long>(out.size()) + count > kMaxSequenceEvents)
      return bad(fmt::format("more than {} events", kMaxSequenceEvents));
    std::string name;
    for (long long id : ids) {
      if (!name.empty()) name.push_back('+');
      name.append(std::to_string(id));
    }
    name.push_back(':');
    name.append(kind);
    out.insert(out.end(), static_cast<size_t>(count), name);
  }
  return out;
}

bool SameContactSequence(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  if (a.empty() || b.empty()) return a.empty() == b.empty();
  // Entries as integers, then each word reduced to its shortest repeating unit.
  std::map<std::string, int> id;
  const auto code = [&](const std::vector<std::string>& w) {
    std::vector<int> out;
    out.reserve(w.size());
    for (const auto& t : Tokens(w)) out.push_back(id.emplace(t.name, static_cast<int>(id.size())).first->second);
    return Primitive(out);
  };
  const std::vector<int> u = code(a), v = code(b);
  if (u.size() != v.size()) return false;
  // u is a rotation of v: u occurs in v v (KMP).
  const auto fail = Borders(u);
  for (size_t i = 0, k = 0; i < 2 * v.size(); ++i) {
    const int c = v[i % v.size()];
    while (k > 0 && c != u[k]) k = fail[k];
    if (c == u[k]) ++k;
    if (k == u.size()) return true;
  }
  return false;
}

std::vector<std::string> ContactSequenceOf(const std::vector<Event>& events, std::vector<size_t>* first) {
  std::vector<std::string> out;
  if (first) first->clear();
  std::vector<int> together;  // the contacts of the entry being built
  const Event* last = nullptr;
  const auto flush = [&] {
    if (!last) return;
    std::sort(together.begin(), together.end());
    std::string name;
    for (int c : together) {
      if (!name.empty()) name.push_back('+');
      name.append(std::to_string(c));
    }
    name.push_back(':');
    name.append(ToString(last->kind));
    out.push_back(std::move(name));
    together.clear();
  };
  for (const Event& e : events) {
    const bool joins = last && e.simultaneous && last->simultaneous && e.t == last->t && e.kind == last->kind;
    if (!joins) {
      flush();
      if (first) first->push_back(static_cast<size_t>(&e - events.data()));
    }
    together.push_back(e.contact);
    last = &e;
  }
  flush();
  return out;
}

size_t CanonicalStart(const std::vector<std::string>& entries) {
  if (entries.size() < 2) return 0;
  const std::vector<Token> tokens = Tokens(entries);
  std::vector<std::string> names;
  names.reserve(tokens.size());
  for (const auto& t : tokens) names.push_back(t.name);
  const std::vector<int> coarse = std::move(Ranked({names}).front());
  // The least rotation of the tokens; when the tokens repeat (u^m), m rotations give it: the one
  // whose m repetitions, each compared as its entries, form the least word of repetitions.
  size_t start = LeastRotation(coarse);
  const size_t unit = Primitive(coarse).size(), m = coarse.size() / unit;
  if (m > 1) {
    std::vector<std::vector<std::string>> blocks(m);
    for (size_t b = 0; b < m; ++b)
      for (size_t t = 0; t < unit; ++t) {
        const Token& tok = tokens[(start + b * unit + t) % tokens.size()];
        for (size_t i = 0; i < tok.size; ++i) blocks[b].push_back(entries[(tok.first + i) % entries.size()]);
      }
    start += LeastRotation(Ranked(blocks)) * unit;
  }
  return tokens[start % tokens.size()].first;
}

std::vector<std::string> CanonicalRotation(const std::vector<std::string>& entries) {
  std::vector<std::string> out(entries);
  std::rotate(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(CanonicalStart(entries)), out.end());
  return out;
}

std::string ContactSequenceText(const std::vector<std::string>& entries) {
  const std::vector<std::string> word = CanonicalRotation(entries);
  std::string out;
  for (size_t i = 0; i < word.size();) {
    size_t k = i + 1;
    while (k < word.size() && word[k] == word[i]) ++k;
    if (!out.empty()) out.push_back(' ');
    out.append(word[i]);
    if (k - i > 1) {
      out.push_back('*');
      out.append(std::to_string(k - i));
    }
    i = k;
  }
  return out;
}

std::vector<std::string> RenameContacts(const std::vector<std::string>& entries, const std::vector<int>& image) {
  std::vector<std::string> out;
  out.reserve(entries.size());
  for (const auto& e : entries) {
    const OrderKey key = KeyOf(e);
    if (key.malformed) {
      out.push_back(e);
      continue;
    }
    std::vector<long long> ids;
    for (long long id : key.contacts)
      ids.push_back(id < static_cast<long long>(image.size()) ? image[static_cast<size_t>(id)] : id);
    std::sort(ids.begin(), ids.end());
    std::string name;
    for (long long id : ids) {
      if (!name.empty()) name.push_back('+');
      name.append(std::to_string(id));
    }
    out.push_back(name + e.substr(e.find(':')));
  }
  return out;
}

}  // namespace vibro

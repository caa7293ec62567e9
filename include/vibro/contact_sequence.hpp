// The contact sequence of a periodic orbit (docs/contacts.md, "Contact sequences are cyclic
// words"): its events over its q periods as "contact:event" ("0:impact 1:impact*3 0+1:impact
// 0:stick 0:release"; OrbitResult::sequence), a cyclic word written in one canonical rotation. Reading a sequence
// written by a person or another tool (a branch CSV's `sequence` column, docs/validation.md),
// comparing two sequences of one periodic orbit, which may start anywhere on it, and writing one.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "vibro/observer.hpp"

namespace vibro {

// The events of `text`, one entry per event with every "*k" expanded, each written "J:kind"
// (the contacts of a simultaneous impact joined by '+' in ascending order, kind one of impact,
// accumulation, stick, release, grazing). `contacts` > 0: every contact index must be below it
// (−1: not checked). At most kMaxSequenceEvents events. Returns nothing and sets `problem` (what
// is wrong and what is expected) when the text is not a sequence; an empty text gives no events.
inline constexpr long long kMaxSequenceEvents = 1000000;
std::optional<std::vector<std::string>> ParseContactSequence(const std::string& text, int contacts,
                                                             std::string& problem);

// Whether two sequences (as ParseContactSequence returns them) describe the same periodic motion:
// the same cyclic order of events, wherever each starts on the orbit (one is a rotation of the
// other) and over however many periods of it each is written (each is reduced to its shortest
// repeating unit). A run of impacts at contact j that ends in j's accumulation point, or directly
// in j's stick (a simulator that ends chattering with a plastic impact below a threshold), is one
// chattering sequence whatever its number of impacts (where its tail of decreasing speeds starts
// is bookkeeping, not another orbit; continuation.hpp's relabels). Empty sequences are equal only
// to each other.
bool SameContactSequence(const std::vector<std::string>& a, const std::vector<std::string>& b);

// The sequence of `events` in order (as ParseContactSequence returns it): one entry per event,
// the contacts of one simultaneous impact (flagged `simultaneous`, at one time) in one entry.
// `first` (when given) receives, for each entry, the index in `events` of its first event.
std::vector<std::string> ContactSequenceOf(const std::vector<Event>& events, std::vector<size_t>* first = nullptr);

// The canonical rotation of a cyclic sequence (docs/contacts.md, "Contact sequences are cyclic
// words"): the rotation whose tokens form the least word, a token being an entry or a whole chattering run at
// one contact (as SameContactSequence groups them), tokens ordered by their contacts (ascending
// lists compared lexicographically: 0 < 0+1 < 1) and then by kind (impact, chattering run,
// accumulation, stick, release, grazing). When the tokens repeat (u^m, over several periods), of
// the m rotations that give that word the one whose repetitions, each compared entry by entry in
// the same order, form the least word. Every rotation of a word gives the same result; the word's
// length and entries are kept (nothing is reduced to its repeating unit).
std::vector<std::string> CanonicalRotation(const std::vector<std::string>& entries);
// Where that rotation starts: the index in `entries` of its first entry (0 for fewer than two
// entries; of several starts giving the one word, the one this computes). CanonicalRotation is
// `entries` rotated to start there; an orbit's events are listed from there (poincare.hpp,
// StartAtCanonicalRotation).
size_t CanonicalStart(const std::vector<std::string>& entries);
// The text of a sequence in its canonical rotation, runs of k equal entries written once with
// "*k" (OrbitResult::sequence, and every sequence vibro writes).
std::string ContactSequenceText(const std::vector<std::string>& entries);

// The sequence with every contact j renamed image[j] (the contacts of a simultaneous impact
// sorted again), e.g. a mirror symmetry's (analysis/mirror_symmetry.hpp). An index not below
// image.size() is kept. Compare the result with SameContactSequence, or bring it to its canonical
// rotation with CanonicalRotation.
std::vector<std::string> RenameContacts(const std::vector<std::string>& entries, const std::vector<int>& image);

}  // namespace vibro

#include "cli/comparison.hpp"

#include <algorithm>

namespace softbake {

const char* verdictName(Verdict verdict) {
  switch (verdict) {
    case Verdict::Pass:
      return "ok";
    case Verdict::Warn:
      return "warn";
    case Verdict::Fail:
      return "DIFFERS";
  }
  return "ok";
}

std::size_t Comparison::count(Verdict verdict) const {
  return std::size_t(std::count_if(items.begin(), items.end(), [&](const ComparedItem& item) {
    return item.verdict == verdict;
  }));
}

Verdict Comparison::worst() const {
  Verdict worst = Verdict::Pass;
  for (const ComparedItem& item : items) worst = std::max(worst, item.verdict);
  return worst;
}

std::vector<const ComparedItem*> reportOrder(const Comparison& comparison) {
  std::vector<const ComparedItem*> order;
  for (const ComparedItem& item : comparison.items) order.push_back(&item);
  std::stable_sort(order.begin(), order.end(), [](const ComparedItem* a, const ComparedItem* b) {
    if (a->verdict != b->verdict) return a->verdict > b->verdict;
    if (a->severity != b->severity) return a->severity > b->severity;
    return a->name < b->name;
  });
  return order;
}

}  // namespace softbake

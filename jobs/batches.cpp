#include "jobs/batches.hpp"

#include "kernel/batch.hpp"

#include <map>
#include <stdexcept>

namespace ff {

std::vector<Batch> make_batches(const std::vector<Model>& models, const std::vector<int>& pending, int lanes) {
  if (lanes < 1) throw std::invalid_argument("make_batches: lanes must be >= 1");
  std::vector<Batch> out;
  std::map<BatchShape, std::size_t> open;  // shape -> its batch still filling
  for (int i : pending) {
    const BatchShape s = batch_shape_of(models[i]);
    auto it = open.find(s);
    if (it == open.end() || static_cast<int>(out[it->second].variants.size()) == lanes) {
      out.push_back({});
      it = open.insert_or_assign(s, out.size() - 1).first;
    }
    out[it->second].variants.push_back(i);
  }
  return out;
}

}  // namespace ff

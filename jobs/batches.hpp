// Lane batches: variants of equal shape (segments, notch sections, substeps, rate, duration,
// integrator, hub drive parts, recorded sensors) grouped W at a time, in eval_id order, so one
// kernel call advances them together.
#pragma once

#include <vector>

#include "kernel/model.hpp"

namespace ff {

struct Batch {
  std::vector<int> variants;   // indices into the study's variants, ascending
};

// Groups `pending` (ascending variant indices) into batches of at most `lanes` variants of one shape.
// Batches of one shape follow the order of that shape's first variant; the result does not
// depend on threads or ranks.
std::vector<Batch> make_batches(const std::vector<Model>& models, const std::vector<int>& pending, int lanes);

}  // namespace ff

// libFuzzer harness of the URDF reader: the input is a URDF file's text (parse_urdf: the depth scan,
// TinyXML, liburdfdom and the tree, which make_tree builds). Every rejection must be a std::exception.
// And the depth scan must hold: a text it lets through is parsed by TinyXML into a tree no deeper than
// kMaxUrdfDepth elements with content and a leaf under the last (measured here without recursion),
// else the harness aborts.
#include <tinyxml.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "common/errors.hpp"
#include "description/urdf.hpp"
#include "fuzz/fuzz_support.hpp"

namespace {

int deepest(const TiXmlDocument& doc) {
  int most = 0;
  std::vector<std::pair<const TiXmlNode*, int>> stack{{&doc, 0}};
  while (!stack.empty()) {
    const auto [node, depth] = stack.back();
    stack.pop_back();
    most = std::max(most, depth);
    for (const TiXmlNode* c = node->FirstChild(); c; c = c->NextSibling())
      if (c->ToElement()) stack.emplace_back(c, depth + 1);
  }
  return most;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = ff::fuzz::text_of(data, size);
  try {
    (void)ff::parse_urdf(text, "fuzz.urdf");
  } catch (const ff::ConfigError& e) {
    if (e.message().find("nested more than") != std::string::npos || e.message().find("not UTF-8") != std::string::npos)
      return 0;  // refused before TinyXML
  } catch (const std::exception&) {
  }
  TiXmlDocument doc;
  doc.Parse(text.c_str());
  if (deepest(doc) > ff::kMaxUrdfDepth + 1) std::abort();  // the scan let a deeper text through
  return 0;
}

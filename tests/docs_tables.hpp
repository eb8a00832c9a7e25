// docs/formats.md's key tables, for the tests that hold the docs to a reader's field tables: the rows
// of the tables headed "| key | unit | required | default | meaning |" in one "## " section, by key.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "common/field_table.hpp"

namespace ff::test {

inline std::map<std::string, std::vector<std::string>> documented_rows(const std::string& section_title) {
  std::ifstream in(std::string(FLEXFARM_SOURCE_DIR) + "/docs/formats.md");
  std::map<std::string, std::vector<std::string>> rows;
  bool section = false, table = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("## ", 0) == 0) section = line == "## " + section_title;
    if (line.rfind("|", 0) != 0) table = false;
    if (line == "| key | unit | required | default | meaning |") table = section;
    if (!table || line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream s(line.substr(1));
    for (std::string cell; std::getline(s, cell, '|');) {
      const auto a = cell.find_first_not_of(' '), b = cell.find_last_not_of(' ');
      cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
    }
    const std::string key = cells.at(0).substr(1, cells.at(0).size() - 2);  // without the backticks
    rows[key] = cells;
  }
  return rows;
}

// Every key of `keys` documented in the section with the reader's unit, requirement and default, and
// no documented key that no reader reads.
inline void expect_documented(const std::string& section_title, const std::vector<KeyDoc>& keys) {
  const auto rows = documented_rows(section_title);
  std::set<std::string> read;
  for (const KeyDoc& k : keys) {
    SCOPED_TRACE(k.key);
    read.insert(k.key);
    const auto it = rows.find(k.key);
    ASSERT_NE(it, rows.end()) << "not in docs/formats.md, section " << section_title;
    ASSERT_GE(it->second.size(), 5u);
    EXPECT_EQ(it->second[1], k.unit);
    EXPECT_EQ(it->second[2], k.required);
    EXPECT_EQ(it->second[3], k.fallback);
  }
  EXPECT_EQ(rows.size(), keys.size());
  for (const auto& [key, cells] : rows)
    EXPECT_TRUE(read.count(key)) << "docs/formats.md documents `" << key << "`, which no reader reads";
}

}  // namespace ff::test

// Tests of the checks every loaded YAML document passes (common/yaml_reader.hpp, load_yaml_text and
// check_unique_keys): keys written twice, keys that are not plain names, aliases that make a cycle or
// expand without end. Each input is the smallest one that showed the fault.
#include "common/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <string>

#include "common/errors.hpp"

namespace {

// Loads `text`, which must fail; returns the error.
ff::ConfigError load_error(const std::string& text) {
  try {
    ff::load_yaml_text(text, "t.yaml");
  } catch (const ff::ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted: " << text;
  return ff::ConfigError("", 0, "", "");
}

}  // namespace

TEST(YamlReader, KeyWrittenTwiceInTextNamesBothLines) {
  const auto e = load_error("a: 1\nb:\n  c: 2\n  c: 3\n");
  EXPECT_EQ(e.file(), "t.yaml");
  EXPECT_EQ(e.key(), "b.c");
  EXPECT_EQ(e.line(), 4);
  EXPECT_NE(e.message().find("lines 3 and 4"), std::string::npos) << e.what();
}

// `&x [*x]` is a list holding itself (yaml-cpp makes the alias the list); walking it overflowed the
// stack: `flexfarm modes` on this file (found while writing fuzz_model).
TEST(YamlReader, AliasInsideTheListItNamesIsAnError) {
  const auto e = load_error("a: &x [*x]\n");
  EXPECT_EQ(e.key(), "a[0]");
  EXPECT_EQ(e.line(), 1);
  EXPECT_NE(e.message().find("cycle"), std::string::npos) << e.what();
}

TEST(YamlReader, AliasInsideTheMapItNamesIsAnError) {
  const auto e = load_error("&x {b: *x}\n");
  EXPECT_EQ(e.key(), "b");
  EXPECT_NE(e.message().find("cycle"), std::string::npos) << e.what();
}

TEST(YamlReader, AnAliasOfASiblingIsNoCycle) {
  const YAML::Node doc = ff::load_yaml_text("a: &x {m: 1}\nb: *x\nc: [*x, *x]\n", "t.yaml");
  EXPECT_EQ(doc["b"]["m"].as<int>(), 1);
  EXPECT_EQ(doc["c"][1]["m"].as<int>(), 1);
}

// Seven levels of ten aliases each: 10^7 values from a few hundred bytes.
TEST(YamlReader, AliasesOfAliasesStopPastTheLimit) {
  std::string text = "l0: &l0 [0, 0, 0, 0, 0, 0, 0, 0, 0, 0]\n";
  for (int i = 1; i <= 7; ++i) {
    const std::string prev = "*l" + std::to_string(i - 1);
    text += "l" + std::to_string(i) + ": &l" + std::to_string(i) + " [";
    for (int k = 0; k < 10; ++k) text += (k ? ", " : "") + prev;
    text += "]\n";
  }
  const auto e = load_error(text);
  EXPECT_NE(e.message().find("more than " + std::to_string(ff::kMaxYamlNodes) + " values"), std::string::npos) << e.what();
}

TEST(YamlReader, AListAsAKeyIsAnError) {
  const auto e = load_error("beam:\n  ? [1, 2]\n  : 3\n");
  EXPECT_EQ(e.key(), "beam");
  EXPECT_EQ(e.line(), 2);
  EXPECT_NE(e.message().find("plain name"), std::string::npos) << e.what();
}

// yaml-cpp stops at 500 levels (no stack overflow) but says only "bad file".
TEST(YamlReader, ListsNestedPastYamlCppsLimitAreOneClearError) {
  EXPECT_NO_THROW(ff::load_yaml_text("x: " + std::string(400, '[') + std::string(400, ']') + "\n", "t.yaml"));
  for (const int depth : {600, 50000}) {
    const auto n = static_cast<std::size_t>(depth);
    const auto e = load_error("segments: 6\nx: " + std::string(n, '[') + std::string(n, ']') + "\ny: 1\n");
    EXPECT_EQ(e.line(), 2) << depth;
    EXPECT_EQ(e.message(), "lists and maps nested more than 499 deep (yaml-cpp's limit)") << depth;
  }
}

TEST(YamlReader, AMapAsAKeyIsAnError) {
  const auto e = load_error("{a: 1}: 2\n");
  EXPECT_NE(e.message().find("plain name"), std::string::npos) << e.what();
}

TEST(YamlReader, SyntaxErrorInTextNamesTheLine) {
  const auto e = load_error("a: 1\nb: [1, 2\n");
  EXPECT_EQ(e.file(), "t.yaml");
  EXPECT_GE(e.line(), 2);
}

// A flag reads YAML's true/false, and the 1 and 0 a study's sweep of it writes; 2 or "maybe" is an
// error naming the key.
TEST(YamlReader, AFlagReadsTrueFalseAndTheSweepsOneAndZero) {
  const auto read = [](const std::string& text) {
    const YAML::Node doc = YAML::Load(text);
    ff::YamlReader r(doc, "t.yaml", "", nullptr);
    bool flag = false;
    r.optional("f", flag);
    return flag;
  };
  EXPECT_TRUE(read("f: true"));
  EXPECT_FALSE(read("f: false"));
  EXPECT_TRUE(read("f: 1"));
  EXPECT_FALSE(read("f: 0"));
  EXPECT_TRUE(read("f: 1.0"));
  for (const char* bad : {"f: 2", "f: 0.5", "f: maybe", "f: [1]"}) {
    try {
      read(bad);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const ff::ConfigError& e) {
      EXPECT_EQ(e.key(), "f") << bad;
      EXPECT_NE(e.message().find("expected true or false"), std::string::npos) << e.what();
    }
  }
}

// Unknown keys name the closest key the reader asked for; a required key missing next to a near miss
// is that near miss's error, not "missing required value" (issue 32, item 15).
TEST(YamlReader, AnUnknownKeyNamesTheClosestKeyTheReaderAskedFor) {
  const YAML::Node doc = ff::load_yaml_text("stiffness: 1\ndampnig: 2\n", "t.yaml");
  ff::YamlReader r(doc, "t.yaml", "joints", nullptr);
  double k = 0, c = 0;
  r.optional("stiffness", k);
  r.optional("damping", c);
  try {
    r.finish();
    ADD_FAILURE() << "accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_STREQ(e.what(), "t.yaml:2: joints.dampnig: unknown key (did you mean `damping`?)");
  }
  try {
    r.only({"stiffness", "damping"});
    ADD_FAILURE() << "accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_STREQ(e.what(), "t.yaml:2: joints.dampnig: unknown key (did you mean `damping`?)");
  }
}

TEST(YamlReader, AMissingRequiredKeyBesideItsMisspellingIsTheMisspelling) {
  const YAML::Node doc = ff::load_yaml_text("stifness: 1\nreference_cell: 2\n", "t.yaml");
  ff::YamlReader r(doc, "t.yaml", "joints", nullptr);
  double k = 0;
  try {
    r.required("stiffness", k);
    ADD_FAILURE() << "accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_STREQ(e.what(), "t.yaml:1: joints.stifness: unknown key (did you mean `stiffness`?)");
  }
  // Nothing near it: missing, as before.
  ff::YamlReader far(doc, "t.yaml", "joints", nullptr);
  try {
    far.required("damping", k);
    ADD_FAILURE() << "accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.message(), "missing required value");
  }
}

TEST(YamlReader, TheUnitsCheckIsInheritedAndTurnedOffByTheFilesKey) {
  const YAML::Node doc = ff::load_yaml_text("units_check: false\nsection: {E: 70}\n", "t.yaml");
  ff::YamlReader top(doc, "t.yaml", "", nullptr);
  EXPECT_TRUE(top.units_check());
  top.read_units_check();
  EXPECT_FALSE(top.units_check());
  EXPECT_FALSE(top.child("section").units_check());
}

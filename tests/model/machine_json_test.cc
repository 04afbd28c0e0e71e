// Machine definition files: the samples load as documented, every bad input
// names the JSON path (or line and column for malformed JSON).
#include "core/model/machine_json.h"

#include <gtest/gtest.h>

#include <sstream>

#include "core/common/input_error.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

TEST(MachineJson, HsuSample) {
  const Machine m = load_machine_json(test::source_path("samples/machines/hsu-3axis.json"));
  EXPECT_EQ(m.axis_count(), 3);
  EXPECT_EQ(m.structure_code(), "[w b Y X Z t]");
  EXPECT_DOUBLE_EQ(m.limits[0].max, 500.0);
  EXPECT_DOUBLE_EQ(m.limits[1].max, 400.0);
  EXPECT_DOUBLE_EQ(m.limits[2].max, 300.0);
  EXPECT_DOUBLE_EQ(m.tool_length_mm, 100.0);
  // Program zero is machine zero: the tip at u = 0 is the workpiece origin.
  const ToolPose v = nominal_forward(m, AxisVector::Zero(3));
  EXPECT_NEAR(v.tip_mm.norm(), 0.0, 1e-12);
  AxisVector u(3);
  u << 100, 200, 50;
  EXPECT_NEAR((nominal_forward(m, u).tip_mm - Eigen::Vector3d(100, 200, 50)).norm(), 0.0, 1e-12);
}

TEST(MachineJson, LeiHsuSample) {
  const Machine m = load_machine_json(test::source_path("samples/machines/lei-hsu-xyzac.json"));
  EXPECT_EQ(m.axis_count(), 5);
  EXPECT_EQ(m.structure_code(), "[w C' A' X' Y' b Z t]");
  EXPECT_TRUE(m.limits[4].unlimited);
  EXPECT_NEAR(m.limits[3].min, -100 * M_PI / 180, 1e-15);
  EXPECT_NEAR(m.limits[3].max, 30 * M_PI / 180, 1e-15);
}

std::string error_of(const std::string& json) {
  std::istringstream in(json);
  try {
    read_machine_json(in, "m.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const char* kGood = R"({"format": "volmap-machine/1",
 "axes": {"X": {"type": "linear", "direction": [1,0,0], "travel_mm": [0, 100]}},
 "workpiece_chain": [], "tool_chain": [{"axis": "X"}], "tool": {"length_mm": 0}})";

TEST(MachineJson, MinimalMachineLoads) { EXPECT_EQ(error_of(kGood), ""); }

TEST(MachineJson, MalformedJsonNamesLineAndColumn) {
  const std::string msg = error_of("{\n  \"format\": \"volmap-machine/1\",\n  \"axes\": {,}\n}");
  EXPECT_EQ(msg.rfind("m.json:3:", 0), 0u) << msg;
  EXPECT_NE(msg.find("malformed JSON"), std::string::npos) << msg;
}

struct BadCase {
  const char* from;
  const char* to;
  const char* path;
  const char* words;
};

// kGood with the first `from` replaced by `to`.
std::string edited(const BadCase& c) {
  std::string doc = kGood;
  const size_t at = doc.find(c.from);
  EXPECT_NE(at, std::string::npos) << c.from;
  if (at != std::string::npos) doc.replace(at, std::string(c.from).size(), c.to);
  return doc;
}

TEST(MachineJson, BadValuesNameTheJsonPath) {
  const BadCase cases[] = {
      {"volmap-machine/1", "volmap-machine/9", "m.json:/format:", "volmap-machine/1"},
      {"[1,0,0]", "[1,1,0]", "m.json:/axes/X/direction:", "unit vector"},
      {"[1,0,0]", "[1,0]", "m.json:/axes/X/direction:", "three numbers"},
      {"[0, 100]", "[100, 0]", "m.json:/axes/X/travel_mm:", "min < max"},
      {"\"linear\"", "\"rotary\"", "m.json:/axes/X/type:", "linear by ISO 841"},
      {"\"linear\"", "\"prismatic\"", "m.json:/axes/X/type:", "\"linear\" or \"rotary\""},
      {"[{\"axis\": \"X\"}]", "[{\"axis\": \"Q\"}]", "m.json:/tool_chain/0/axis:", "axis letter"},
      {"[{\"axis\": \"X\"}]", "[]", "m.json:/axes/X:", "in no chain"},
      {"\"workpiece_chain\": []", "\"workpiece_chain\": [{\"axis\": \"X\"}]",
       "m.json:/tool_chain/0/axis:", "twice"},
      {"\"length_mm\": 0", "\"length_mm\": -5", "m.json:/tool/length_mm:", "negative"},
      {"\"length_mm\": 0", "\"length\": 0", "m.json:/tool/length:", "did you mean \"length_mm\""},
  };
  for (const BadCase& c : cases) {
    const std::string msg = error_of(edited(c));
    EXPECT_EQ(msg.rfind(c.path, 0), 0u) << msg;
    EXPECT_NE(msg.find(c.words), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
  }
}

// A misspelt key would silently change the machine (issue 23: a
// `workpiece_orign_mm` left the workpiece origin at zero): every key of
// every object is known, or the file is refused at the key's JSON path with
// the nearest known key.
TEST(MachineJson, MisspeltKeysAreRefusedWithTheNearestKey) {
  const BadCase cases[] = {
      {"\"tool\":", "\"workpiece_orign_mm\": [1, 2, 3], \"tool\":", "m.json:/workpiece_orign_mm:",
       "did you mean \"workpiece_origin_mm\""},
      {"\"travel_mm\"", "\"home_mm\": 5, \"travel_mm\"", "", ""},  // a known key: loads
      {"\"travel_mm\": [0, 100]", "\"travel_mm\": [0, 100], \"hom_mm\": 5",
       "m.json:/axes/X/hom_mm:", "did you mean \"home_mm\""},
      {"{\"axis\": \"X\"}", "{\"axis\": \"X\", \"ofset_mm\": [0, 0, 0]}",
       "m.json:/tool_chain/0/ofset_mm:", "did you mean \"offset_mm\""},
      {"\"length_mm\": 0", "\"length_mm\": 0, \"axsi\": [0, 0, 1]",
       "m.json:/tool/axsi:", "did you mean \"axis\""},
      {"\"tool\":", "\"coolant\": true, \"tool\":", "m.json:/coolant:",
       "unknown key \"coolant\"; expected one of: format, name"},
  };
  for (const BadCase& c : cases) {
    const std::string msg = error_of(edited(c));
    if (std::string(c.path).empty()) {
      EXPECT_EQ(msg, "") << c.to;  // a known key loads
      continue;
    }
    EXPECT_EQ(msg.rfind(c.path, 0), 0u) << msg;
    EXPECT_NE(msg.find(c.words), std::string::npos) << msg;
  }
}

TEST(MachineJson, StructureCodeMustMatchTheChains) {
  std::string doc = kGood;
  doc.insert(1, "\"structure\": \"[w X' b t]\", ");
  const std::string msg = error_of(doc);
  EXPECT_EQ(msg.rfind("m.json:/structure:", 0), 0u) << msg;
  EXPECT_NE(msg.find("[w b X t]"), std::string::npos) << msg;
}

TEST(MachineJson, MissingFileIsAnInputError) {
  EXPECT_THROW(load_machine_json("/nonexistent/m.json"), InputError);
}

}  // namespace
}  // namespace volmap

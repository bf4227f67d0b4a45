// Config schemas: defaults, overrides and every error a user can make, with its location.
#include <gtest/gtest.h>

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/config.h"
#include "core/error.h"
#include "core/yaml_json.h"
#include "tests/support/scratch_dir.h"

using namespace cgsr;
using namespace cgsr::config;

namespace {
struct Camera {
  double fov = 60.0;
  std::vector<double> position{0, 0, 0};
};
struct Light {
  std::string kind = "point";
  double intensity = 1.0;
};
struct SceneOptions {
  std::string name;
  int frames = 300;
  bool shadows = false;
  std::vector<std::string> channels{"depth"};
  Camera camera;
  std::vector<Light> lights;
  Block source;
};

Schema<Camera> camera_schema() {
  Schema<Camera> s;
  s.field("fov", &Camera::fov, "vertical field of view in degrees").range(1, 179);
  s.field("position", &Camera::position, "x, y, z").check([](const auto& v) { return v.size() == 3; },
                                                           "expected 3 numbers");
  return s;
}
Schema<Light> light_schema() {
  Schema<Light> s;
  s.field("kind", &Light::kind, "light type").one_of({"point", "directional"});
  s.field("intensity", &Light::intensity, "intensity").at_least(0);
  return s;
}
Schema<SceneOptions> scene_schema() {
  Schema<SceneOptions> s;
  s.field("name", &SceneOptions::name, "scene name").required();
  s.field("frames", &SceneOptions::frames, "frames to render").range(1, 100000);
  s.field("shadows", &SceneOptions::shadows, "shadow maps");
  s.field("channels", &SceneOptions::channels, "rendering channels").one_of({"depth", "normal", "edge"});
  s.section("camera", &SceneOptions::camera, camera_schema(), "camera");
  s.list("lights", &SceneOptions::lights, light_schema(), "lights");
  s.block("source", &SceneOptions::source, "scene source");
  return s;
}

SceneOptions parse(const std::string& yaml, const std::vector<std::string>& sets = {}) {
  Document doc = Document::parse(yaml, "scene.yaml");
  for (const auto& s : sets) doc.apply_override(s);
  return parse_document(doc, scene_schema());
}

std::string error_of(const std::string& yaml, const std::vector<std::string>& sets = {}) {
  try {
    parse(yaml, sets);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}
}  // namespace

TEST(Config, DefaultsComeFromCode) {
  const auto s = parse("name: hall\n");
  EXPECT_EQ(s.name, "hall");
  EXPECT_EQ(s.frames, 300);
  EXPECT_EQ(s.camera.fov, 60.0);
  EXPECT_TRUE(s.lights.empty());
}

TEST(Config, ParsesNestedSectionsAndLists) {
  const auto s = parse(
      "name: hall\nframes: 12\nshadows: true\nchannels: [depth, edge]\n"
      "camera: {fov: 75, position: [1, 2, 3]}\nlights:\n  - {kind: directional, intensity: 2}\n  - {}\n");
  EXPECT_EQ(s.frames, 12);
  EXPECT_TRUE(s.shadows);
  EXPECT_EQ(s.channels, (std::vector<std::string>{"depth", "edge"}));
  EXPECT_EQ(s.camera.position[2], 3.0);
  ASSERT_EQ(s.lights.size(), 2u);
  EXPECT_EQ(s.lights[0].kind, "directional");
  EXPECT_EQ(s.lights[1].kind, "point");
}

TEST(Config, UnknownKeySuggestsTheClosestAndGivesLineAndColumn) {
  const auto e = error_of("name: hall\ncamera:\n  fvo: 70\n");
  EXPECT_NE(e.find("scene.yaml:3:3"), std::string::npos) << e;
  EXPECT_NE(e.find("camera.fvo"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'fov'"), std::string::npos) << e;
}

TEST(Config, AKeyThatIsAListOrAMapIsAnErrorWithItsLocation) {
  // Found by fuzz_config: yaml-cpp's bad-conversion exception escaped the schema.
  auto e = error_of("name: hall\ncamera:\n  ? [fov, near]\n  : 70\n");
  EXPECT_NE(e.find("scene.yaml:3:5"), std::string::npos) << e;
  EXPECT_NE(e.find("a key must be a name, got a list"), std::string::npos) << e;
  e = error_of("name: hall\n{frames: 3}: 2\n");
  EXPECT_NE(e.find("a key must be a name, got a map"), std::string::npos) << e;
}

TEST(Config, WrongTypeOutOfRangeAndMissingKeys) {
  auto e = error_of("name: hall\nframes: many\n");
  EXPECT_NE(e.find("scene.yaml:2:9: frames: expected an integer, got 'many'"), std::string::npos) << e;
  e = error_of("name: hall\nframes: 0\n");
  EXPECT_NE(e.find("frames: '0' is out of range [1, 100000]"), std::string::npos) << e;
  e = error_of("name: hall\ncamera: {fov: 500}\n");
  EXPECT_NE(e.find("camera.fov: '500' is out of range [1, 179]"), std::string::npos) << e;
  e = error_of("frames: 3\n");
  EXPECT_NE(e.find("missing required key 'name'"), std::string::npos) << e;
  e = error_of("name: hall\nlights: [{kind: spot}]\n");
  EXPECT_NE(e.find("lights[0].kind: 'spot' is not one of: point, directional"), std::string::npos) << e;
  e = error_of("name: hall\ncamera: {position: [1, 2]}\n");
  EXPECT_NE(e.find("expected 3 numbers"), std::string::npos) << e;
  e = error_of("name: hall\nframes: .nan\n");
  EXPECT_NE(e.find("frames: expected an integer"), std::string::npos) << e;
}

TEST(Config, NonFiniteNumbersAreRejected) {
  const auto e = error_of("name: hall\ncamera: {fov: .inf}\n");
  EXPECT_NE(e.find("expected a finite number"), std::string::npos) << e;
}

TEST(Config, InvalidYamlNamesTheLine) {
  const auto e = error_of("name: hall\ncamera: {fov: 3\n");
  EXPECT_NE(e.find("scene.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("invalid YAML"), std::string::npos) << e;
}

TEST(Config, OverridesParseAsYamlAndCreateNestedKeys) {
  const auto s = parse("name: hall\n", {"frames=42", "camera.position=[4, 5, 6]", "shadows=true"});
  EXPECT_EQ(s.frames, 42);
  EXPECT_EQ(s.camera.position[0], 4.0);
  EXPECT_TRUE(s.shadows);
}

TEST(Config, OverrideErrorsNameTheAssignment) {
  auto e = error_of("name: hall\n", {"frames=lots"});
  EXPECT_NE(e.find("--set frames=lots: frames: expected an integer"), std::string::npos) << e;
  e = error_of("name: hall\n", {"framez=3"});
  EXPECT_NE(e.find("--set framez=3"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'frames'"), std::string::npos) << e;
  EXPECT_THROW(parse("name: hall\n", {"frames"}), Error);
  EXPECT_THROW(parse("name: hall\n", {"name.inner=3"}), Error);  // name is a scalar
}

// An unknown section made by --set (`open.derive=[edge]` where there is no `open`) is located at
// the assignment; it used to be reported at "<defaults>".
TEST(Config, AnUnknownSectionFromSetNamesTheAssignment) {
  const auto e = error_of("name: hall\n", {"open.derive=[edge]"});
  EXPECT_EQ(e.find("<defaults>"), std::string::npos) << e;
  EXPECT_NE(e.find("--set open.derive=[edge]: open: unknown key 'open'"), std::string::npos) << e;
}

// A whole number too large for the field is out of range, not "expected an integer"; whole
// numbers written with an exponent are integers.
TEST(Config, LargeNumbersAreOutOfRangeNotOfAWrongType) {
  auto e = error_of("name: hall\n", {"frames=1e15"});
  EXPECT_NE(e.find("--set frames=1e15: frames: '1e15' is out of range [1, 100000]"), std::string::npos) << e;
  e = error_of("name: hall\nframes: 99999999999999999999\n");
  EXPECT_NE(e.find("scene.yaml:2:9: frames: '99999999999999999999' is out of range [1, 100000]"), std::string::npos)
      << e;
  e = error_of("name: hall\nframes: 2.5\n");
  EXPECT_NE(e.find("frames: expected an integer, got '2.5'"), std::string::npos) << e;
  EXPECT_EQ(parse("name: hall\nframes: 1e3\n").frames, 1000);
  // An element of a list given by --set is located at the assignment, not in the file.
  e = error_of("name: hall\nlights: [{}]\n", {"lights=[{intensity: -2}]"});
  EXPECT_NE(e.find("--set lights=[{intensity: -2}]: lights[0].intensity: '-2' is out of range [0, inf)"),
            std::string::npos)
      << e;
  e = error_of("name: hall\nlights: [{intensity: -1}]\n");
  EXPECT_NE(e.find("lights[0].intensity: '-1' is out of range [0, inf)"), std::string::npos) << e;
  // A field without a range still names its type's bounds.
  struct Wide {
    int small = 0;
  };
  Schema<Wide> schema;
  schema.field("small", &Wide::small, "an int");
  try {
    parse_document(Document::parse("small: 1e12\n", "w.yaml"), schema);
    FAIL();
  } catch (const Error& err) {
    EXPECT_NE(std::string(err.what()).find("small: '1e12' is out of range [-2147483648, 2147483647]"), std::string::npos)
        << err.what();
  }
}

TEST(Config, TypedBlocksKeepTheirLocation) {
  const auto s = parse("name: hall\nsource:\n  type: procedural\n  rooms: 3\n");
  EXPECT_EQ(block_type(s.source), "procedural");
  struct Procedural {
    int rooms = 1;
  };
  Schema<Procedural> schema;
  schema.field("rooms", &Procedural::rooms, "rooms").range(1, 10);
  EXPECT_EQ(parse_block_options(s.source, schema).rooms, 3);

  const auto bad = parse("name: hall\nsource:\n  type: procedural\n  romos: 3\n");
  try {
    parse_block_options(bad.source, schema);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene.yaml:4:3: source.romos"), std::string::npos) << e.what();
  }
  const auto untyped = parse("name: hall\nsource: {rooms: 3}\n");
  EXPECT_THROW(block_type(untyped.source), Error);
}

TEST(Config, EmitRoundTrips) {
  const auto s = parse("name: hall\nframes: 7\nlights: [{kind: directional}]\ncamera: {fov: 33}\n");
  const std::string text = to_yaml(scene_schema().emit(s));
  const auto again = parse_document(Document::parse(text, "emitted"), scene_schema());
  EXPECT_EQ(again.frames, 7);
  EXPECT_EQ(again.camera.fov, 33.0);
  ASSERT_EQ(again.lights.size(), 1u);
  EXPECT_EQ(again.lights[0].kind, "directional");
}

TEST(Config, OmittedKeysLeaveTheEmittedConfigWhileTheyDoNotApply) {
  Schema<SceneOptions> schema = scene_schema();
  schema.omit_when("lights", [](const SceneOptions& o) { return o.lights.empty(); });
  const auto without = parse_document(Document::parse("name: hall\n", "a"), schema);
  const YAML::Node a = schema.emit(without);
  EXPECT_FALSE(a["lights"]);
  EXPECT_TRUE(a["frames"]);
  const auto with = parse_document(Document::parse("name: hall\nlights: [{kind: point}]\n", "b"), schema);
  EXPECT_EQ(schema.emit(with)["lights"].size(), 1u);
  // The emitted config still parses to the same options.
  EXPECT_TRUE(parse_document(Document::parse(to_yaml(a), "emitted"), schema).lights.empty());
}

TEST(Config, MissingFileIsAnError) {
  try {
    Document::load_file("/nonexistent/x.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/x.yaml: no such config file"), std::string::npos);
  }
}

namespace {
struct Job {
  std::string name;
  Camera camera;  // its keys sit at the top level of a job
};
Schema<Job> job_schema(const Schema<Camera>& camera = camera_schema()) {
  Schema<Job> s;
  s.field("name", &Job::name, "job name");
  s.inline_section(&Job::camera, camera);
  s.moved_block("camera");
  return s;
}
}  // namespace

TEST(Config, AnInlineSectionReadsAtTheTopAndItsFormerBlockStillReads) {
  const Job flat = parse_document(Document::parse("name: a\nfov: 30\n", "job.yaml"), job_schema());
  EXPECT_DOUBLE_EQ(flat.camera.fov, 30);
  const std::string emitted = to_yaml(job_schema().emit(flat));
  EXPECT_EQ(emitted.find("camera"), std::string::npos) << emitted;
  EXPECT_NE(emitted.find("fov: 30"), std::string::npos) << emitted;

  // Read with a warning, once, naming the file and the old and new key.
  std::ostringstream log;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  spdlog::default_logger()->sinks().push_back(sink);
  const auto doc = Document::parse("name: a\ncamera: {fov: 30}\n", "job.yaml");
  const Job moved = parse_document(doc, job_schema());
  parse_document(doc, job_schema());
  spdlog::default_logger()->sinks().pop_back();
  EXPECT_DOUBLE_EQ(moved.camera.fov, 30);
  const std::string warning = log.str();
  EXPECT_NE(warning.find("job.yaml:2:1: 'camera' is deprecated: write its keys directly at the top level ('fov' "
                         "instead of 'camera.fov')"),
            std::string::npos)
      << warning;
  EXPECT_EQ(warning.find("deprecated"), warning.rfind("deprecated")) << warning;
  // Errors inside the former block keep its position; a key given both ways is an error.
  try {
    parse_document(Document::parse("camera: {fov: 300}\n", "job.yaml"), job_schema());
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("job.yaml:1:15: fov: '300' is out of range [1, 179]"), std::string::npos) << e.what();
  }
  try {
    parse_document(Document::parse("fov: 30\ncamera: {fov: 40}\n", "job.yaml"), job_schema());
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("camera.fov: is also given as 'fov'"), std::string::npos) << e.what();
  }
}

namespace {
// A camera whose field of view was once `angle` (an older shape, upgraded with a warning),
// inlined into a job: the upgrade must reach the job's top level, where the camera keys now sit.
Schema<Camera> camera_schema_with_former_angle() {
  Schema<Camera> s = camera_schema();
  s.upgrade([](const YAML::Node& map, const Cursor& at) {
    if (!map || !map.IsMap() || !map["angle"]) return map;
    warn_deprecated(at.doc ? at.doc->locate(map["angle"]) : at.path,
                    "'" + at.child("angle").path + "' is deprecated: write '" + at.child("fov").path + "'");
    YAML::Node out(YAML::NodeType::Map);
    for (const auto& kv : map) out.force_insert(kv.first.Scalar() == "angle" ? YAML::Node("fov") : kv.first, kv.second);
    return out;
  });
  return s;
}
}  // namespace

TEST(Config, AnInlineSectionCarriesItsSchemasUpgrades) {
  const Schema<Job> schema = job_schema(camera_schema_with_former_angle());
  std::ostringstream log;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  spdlog::default_logger()->sinks().push_back(sink);
  const Job flat = parse_document(Document::parse("name: a\nangle: 30\n", "new-job.yaml"), schema);
  // The same old key inside the section's former block: lifted first, then upgraded.
  const Job nested = parse_document(Document::parse("name: b\ncamera: {angle: 40}\n", "old-job.yaml"), schema);
  spdlog::default_logger()->sinks().pop_back();
  EXPECT_DOUBLE_EQ(flat.camera.fov, 30);
  EXPECT_DOUBLE_EQ(nested.camera.fov, 40);
  const std::string warning = log.str();
  EXPECT_NE(warning.find("new-job.yaml:2:8: 'angle' is deprecated: write 'fov'"), std::string::npos) << warning;
  EXPECT_NE(warning.find("old-job.yaml:2:17: 'angle' is deprecated: write 'fov'"), std::string::npos) << warning;
  EXPECT_NE(warning.find("old-job.yaml:2:1: 'camera' is deprecated"), std::string::npos) << warning;
  // Emitted in the current shape.
  const std::string emitted = to_yaml(schema.emit(flat));
  EXPECT_EQ(emitted.find("angle"), std::string::npos) << emitted;
  EXPECT_NE(emitted.find("fov: 30"), std::string::npos) << emitted;
  // The upgraded key is checked like a current one, at the old key's value.
  try {
    parse_document(Document::parse("angle: 300\n", "new-job.yaml"), schema);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("new-job.yaml:1:8: fov: '300' is out of range [1, 179]"), std::string::npos) << e.what();
  }
}

TEST(Config, AKeyThatIsAListReachesJsonAsItsYamlText) {
  // A raw block keeps such a key until its schema rejects it; recording the config must not fail
  // first (`cgsr run` with `train: {? [a, b]: 1}` was an internal yaml-cpp error).
  const auto doc = Document::parse("train: {? [a, b]: 1, ~: 2, steps: 3}\n", "run.yaml");
  const auto j = yaml_to_json(doc.root());
  EXPECT_EQ(j["train"]["[a, b]"], 1);
  EXPECT_EQ(j["train"]["~"], 2);
  EXPECT_EQ(j["train"]["steps"], 3);
}

// Duplicate keys were accepted silently (yaml-cpp reads the first); now an error naming both lines.
TEST(Config, DuplicateKeysAreAnErrorNamingBothLines) {
  auto e = error_of("name: hall\nframes: 3\ncamera: {fov: 70}\nframes: 4\n");
  EXPECT_NE(e.find("scene.yaml:4:1: duplicate key 'frames' (first at line 2); keep one"), std::string::npos) << e;
  e = error_of("name: hall\ncamera:\n  fov: 70\n  fov: 80\n");
  EXPECT_NE(e.find("scene.yaml:4:3: duplicate key 'fov' (first at line 3)"), std::string::npos) << e;
  e = error_of("name: hall\n", {"camera={fov: 1, fov: 2}"});
  EXPECT_NE(e.find("duplicate key 'fov'"), std::string::npos) << e;
}

// A 10 MB list took 1.68 GB and --check called it valid; 50 MB died with std::bad_alloc. The size
// is checked before yaml-cpp reads the text, lists and values right after, before any schema.
TEST(Config, ConfigsAreBoundedBeforeTheyAreParsed) {
  std::string big = "name: hall\nlights: [";
  while (big.size() <= (size_t{1} << 20)) big += "{}, ";
  big += "{}]\n";
  auto e = error_of(big);
  EXPECT_NE(e.find("scene.yaml: the config is " + std::to_string(big.size()) +
                   " bytes, more than the limit of 1048576 (1 MiB)"),
            std::string::npos)
      << e.substr(0, 300);
  std::string list = "name: hall\ncamera: {position: [";
  for (int i = 0; i < 100001; ++i) list += "0,";
  list += "0]}\n";
  e = error_of(list);
  EXPECT_NE(e.find("scene.yaml:2:"), std::string::npos) << e.substr(0, 300);
  EXPECT_NE(e.find("a list of 100002 items, more than the limit of 100000"), std::string::npos)
      << e.substr(0, 300);
  // Aliases reuse a node without copying it: counted as often as they are used.
  std::string laughs = "l0: &l0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n";
  for (int level = 1; level <= 7; ++level) {  // 10^8 values from a few hundred bytes
    const std::string previous = "*l" + std::to_string(level - 1);
    laughs += "l" + std::to_string(level) + ": &l" + std::to_string(level) + " [" + previous;
    for (int i = 1; i < 10; ++i) laughs += ", " + previous;
    laughs += "]\n";
  }
  e = error_of(laughs);
  EXPECT_NE(e.find("more than 1000000 values (counting each use of an alias)"), std::string::npos) << e;
  // A file too large is refused before it is read.
  const auto file = test::scratch_dir("big-config") / "big.yaml";
  { std::ofstream(file) << big; }
  try {
    Document::load_file(file);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& err) {
    EXPECT_NE(std::string(err.what()).find("more than the limit of 1048576"), std::string::npos) << err.what();
  }
  std::filesystem::remove(file);
}

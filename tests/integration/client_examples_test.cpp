// Runs every client example of client-examples/ against a live server; each output must equal
// the CLI's output for the same input and parameters, byte for byte.
#include "http_fixture.h"

namespace mdn::test {
namespace {

class ClientExamples : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { server_ = new ServerProcess({"--workers", "2"}); }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  void SetUp() override {
    ASSERT_TRUE(server_->started()) << server_->log();
    dir_ = temp_dir("clients");
    write_file(dir_ + "/in.off", noisy_sphere_off(2, 21));
    const auto [code, out] = run_command(cli_binary() + " --params " + shell_quote(params_) + " " +
                                         shell_quote(dir_ + "/in.off") + " " + shell_quote(dir_ + "/cli.off") + " 2>&1");
    ASSERT_EQ(code, 0) << out;
    expected_ = read_file(dir_ + "/cli.off");
    ASSERT_FALSE(expected_.empty());
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string env() const { return "MDN_URL=http://127.0.0.1:" + std::to_string(server_->port()) + " "; }
  std::string example(const std::string& rel) const { return source_dir() + "/client-examples/" + rel; }

  static ServerProcess* server_;
  std::string dir_, expected_;
  const std::string params_ = R"({"n_normal":15,"n_vertex":12})";
};
ServerProcess* ClientExamples::server_ = nullptr;

TEST_F(ClientExamples, Curl) {
  const auto [code, out] = run_command(env() + "bash " + shell_quote(example("curl/denoise.sh")) + " " +
                                       shell_quote(dir_ + "/in.off") + " " + shell_quote(dir_ + "/out.off") + " " +
                                       shell_quote(params_) + " 2>&1");
  ASSERT_EQ(code, 0) << out;
  EXPECT_EQ(read_file(dir_ + "/out.off"), expected_);
}

TEST_F(ClientExamples, PythonSyncAndAsync) {
  for (const char* mode : {"", " --async"}) {
    const auto [code, out] = run_command(env() + "python3 " + shell_quote(example("python/denoise_client.py")) + " " +
                                         shell_quote(dir_ + "/in.off") + " " + shell_quote(dir_ + "/out.off") + " " +
                                         shell_quote(params_) + mode + " 2>&1");
    ASSERT_EQ(code, 0) << out;
    EXPECT_EQ(read_file(dir_ + "/out.off"), expected_) << mode;
  }
  // Errors come back as problem+json and a failing exit status.
  const auto [code, out] = run_command(env() + "python3 " + shell_quote(example("python/denoise_client.py")) + " " +
                                       shell_quote(dir_ + "/in.off") + " " + shell_quote(dir_ + "/bad.off") +
                                       " '{\"alpha\":-1}' 2>&1");
  EXPECT_NE(code, 0);
  EXPECT_NE(out.find("alpha"), std::string::npos) << out;
}

// The Python client's --help, from the repository root and from its own folder (it used to die
// with an IndexError); a wrong argument count is a usage error (2).
TEST_F(ClientExamples, PythonHelpFromAnyFolder) {
  for (const std::string& folder : {std::string(source_dir()), std::string(source_dir()) + "/client-examples"}) {
    const std::string script = folder == source_dir() ? "client-examples/python/denoise_client.py" : "python/denoise_client.py";
    const auto [code, out] = run_command("cd " + shell_quote(folder) + " && python3 " + script + " --help 2>&1");
    EXPECT_EQ(code, 0) << folder << ": " << out;
    EXPECT_NE(out.find("Usage:"), std::string::npos) << out;
    const auto [bad, text] = run_command("cd " + shell_quote(folder) + " && python3 " + script + " only-one 2>&1");
    EXPECT_EQ(bad, 2) << text;
  }
}

TEST_F(ClientExamples, NodeFetch) {
  const auto [code, out] = run_command(env() + "node " + shell_quote(example("node/denoise_client.mjs")) + " " +
                                       shell_quote(dir_ + "/in.off") + " " + shell_quote(dir_ + "/out.off") + " " +
                                       shell_quote(params_) + " 2>&1");
  ASSERT_EQ(code, 0) << out;
  EXPECT_EQ(read_file(dir_ + "/out.off"), expected_);
}

TEST_F(ClientExamples, NodeGltfTransformPipelineStep) {
  // As client-examples/README.md says: its own pinned packages (npm ci --prefix
  // client-examples/node), run in place from the repository root.
  const fs::path modules = fs::path(source_dir()) / "client-examples/node/node_modules";
  ASSERT_TRUE(fs::exists(modules / "@gltf-transform/core")) << "run scripts/install-deps.sh build test";
  // A GLB to start from: the server converts the noisy OFF (no denoising iterations).
  auto c = server_->client();
  auto glb = c->Post("/v1/denoise", {{"X-Denoise-Params", R"({"n_aniso":0,"n_normal":0,"n_vertex":0,"output":{"format":"glb"}})"}},
                     read_file(dir_ + "/in.off"), "model/x-off");
  ASSERT_TRUE(glb);
  ASSERT_EQ(glb->status, 200) << glb->body;
  write_file(dir_ + "/in.glb", glb->body);
  const auto [code, out] = run_command("cd " + shell_quote(source_dir()) + " && " + env() + "node client-examples/node/gltf_transform_denoise.mjs " +
                                       shell_quote(dir_ + "/in.glb") + " " + shell_quote(dir_ + "/out.glb") + " " +
                                       shell_quote(params_) + " 2>&1");
  ASSERT_EQ(code, 0) << out;
  const std::string result = read_file(dir_ + "/out.glb");
  ASSERT_EQ(result.substr(0, 4), "glTF");
  // Read back by the server itself: same face count as the input.
  auto back = c->Post("/v1/denoise", {{"X-Denoise-Params", R"({"n_aniso":0,"n_normal":0,"n_vertex":0})"}}, result,
                      "model/gltf-binary");
  ASSERT_TRUE(back);
  ASSERT_EQ(back->status, 200) << back->body;
  EXPECT_EQ(back->get_header_value("X-Denoise-Faces"), "320");
  EXPECT_NE(result, glb->body);  // the positions changed
}

TEST_F(ClientExamples, CppHttplibClient) {
  const std::string binary = build_dir() + "/tests/integration/denoise_client_example";
  ASSERT_TRUE(fs::exists(binary)) << binary;
  const auto [code, out] = run_command(shell_quote(binary) + " 127.0.0.1 " + std::to_string(server_->port()) + " " +
                                       shell_quote(dir_ + "/in.off") + " " + shell_quote(dir_ + "/out.off") + " " +
                                       shell_quote(params_) + " 2>&1");
  ASSERT_EQ(code, 0) << out;
  EXPECT_EQ(read_file(dir_ + "/out.off"), expected_);
}

}  // namespace
}  // namespace mdn::test

// Runs every client example of client-examples/ against a live server; each output must equal
// the CLI's output for the same input and parameters, byte for byte.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>

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

// A loopback port nobody listens on (bound, then closed).
int closed_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof addr;
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    close(fd);
    return 1;
  }
  close(fd);
  return ntohs(addr.sin_port);
}

// The four examples run the same way: input, output, parameters, against a server's port.
class EveryClient : public ClientExamples, public ::testing::WithParamInterface<std::string> {
 protected:
  std::pair<int, std::string> run_client(const std::string& input, const std::string& output, const std::string& params,
                                         int port) const {
    const std::string files = shell_quote(input) + " " + shell_quote(output) + " " + shell_quote(params);
    const std::string url = "MDN_URL=http://127.0.0.1:" + std::to_string(port) + " ";
    const std::string& kind = GetParam();
    std::string command;
    if (kind == "curl") command = url + "bash " + shell_quote(example("curl/denoise.sh")) + " " + files;
    if (kind == "python") command = url + "python3 " + shell_quote(example("python/denoise_client.py")) + " " + files;
    if (kind == "node") command = url + "node " + shell_quote(example("node/denoise_client.mjs")) + " " + files;
    if (kind == "cpp")
      command = shell_quote(build_dir() + "/tests/integration/denoise_client_example") + " 127.0.0.1 " + std::to_string(port) +
                " " + files;
    return run_command(command + " 2>&1");
  }
  // A mistake's answer: the exit status, and one line that says what went wrong.
  void expect_one_line(const std::pair<int, std::string>& r, int code, const std::vector<std::string>& words) const {
    const auto& [status, out] = r;
    EXPECT_EQ(status, code) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << "not one line:\n" << out;
    for (const auto& w : words) EXPECT_NE(out.find(w), std::string::npos) << "no \"" << w << "\" in:\n" << out;
    for (const char* noise : {"Traceback", "TypeError", "unbound variable", "at file://", "curl: ("})
      EXPECT_EQ(out.find(noise), std::string::npos) << out;
  }
};

// Issue 34: `denoise.sh in.off out.glb` wrote OFF text into out.glb (all four clients did): the
// output's extension sets output.format, so each writes what the CLI writes to that name.
TEST_P(EveryClient, TheOutputsExtensionSetsItsFormat) {
  for (const std::string ext : {"glb", "ply", "stl"}) {
    const std::string cli = dir_ + "/cli." + ext;
    const auto [cli_code, cli_out] = run_command(cli_binary() + " --params " + shell_quote(params_) + " " +
                                                 shell_quote(dir_ + "/in.off") + " " + shell_quote(cli) + " 2>&1");
    ASSERT_EQ(cli_code, 0) << cli_out;
    const auto [code, out] = run_client(dir_ + "/in.off", dir_ + "/out." + ext, params_, server_->port());
    ASSERT_EQ(code, 0) << out;
    EXPECT_EQ(read_file(dir_ + "/out." + ext), read_file(cli)) << ext;
  }
  // A format in the parameters that disagrees with the extension is refused before sending.
  expect_one_line(run_client(dir_ + "/in.off", dir_ + "/out.glb", R"({"output":{"format":"ply"}})", server_->port()), 2,
                  {"output.format", "out.glb"});
}

// Issue 34: a missing input gave "unbound variable" (curl), a traceback (Python), a TypeError
// (Node) and "empty body" (C++). Every client checks its arguments before sending.
TEST_P(EveryClient, MistakesInTheArgumentsAreOneLineAndExitTwo) {
  const int port = server_->port();
  expect_one_line(run_client(dir_ + "/missing.off", dir_ + "/out.off", "{}", port), 2, {"cannot read", "missing.off"});
  expect_one_line(run_client(dir_ + "/in.off", dir_ + "/out.xyz", "{}", port), 2, {"out.xyz", "names no format"});
  expect_one_line(run_client(dir_ + "/in.off", dir_ + "/no/such/out.off", "{}", port), 2, {"does not exist"});
  expect_one_line(run_client(dir_ + "/in.off", dir_ + "/out.off", "{not json", port), 2, {"parameters"});
  EXPECT_FALSE(fs::exists(dir_ + "/out.off"));
}

TEST_P(EveryClient, AnUnreachableServerIsOneLineAndExitOne) {
  expect_one_line(run_client(dir_ + "/in.off", dir_ + "/out.off", "{}", closed_port()), 1, {"cannot reach the server"});
  EXPECT_FALSE(fs::exists(dir_ + "/out.off"));
}

TEST_P(EveryClient, AProblemAnswerIsOneLineAndExitOne) {
  expect_one_line(run_client(dir_ + "/in.off", dir_ + "/out.off", R"({"alpha":-1})", server_->port()), 1,
                  {"the server answered 4", "alpha"});
  write_file(dir_ + "/junk.off", "this is not a mesh\n");
  expect_one_line(run_client(dir_ + "/junk.off", dir_ + "/out.off", "{}", server_->port()), 1, {"the server answered 4"});
  EXPECT_FALSE(fs::exists(dir_ + "/out.off"));
}

INSTANTIATE_TEST_SUITE_P(Examples, EveryClient, ::testing::Values("curl", "python", "node", "cpp"),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace mdn::test

// The service's own request and response (http_message.h): what the route handlers work on
// without cpp-httplib, and a handler (the web page) run on them directly.
#include "server/http/transport/http_message.h"

#include <gtest/gtest.h>

#include <string>

#include "server/http/routes/http_support.h"
#include "server/http/problem.h"
#include "server/http/routes/web_routes.h"

namespace mdn::http {
namespace {

TEST(HttpMessage, HeaderNamesCompareWithoutCaseAndTheFirstValueIsRead) {
  Request req;
  req.headers.emplace("content-length", "12");
  req.headers.emplace("X-Tag", "a");
  req.headers.emplace("x-tag", "b");
  req.params.emplace("wait", "5");
  EXPECT_TRUE(req.has_header("Content-Length"));
  EXPECT_EQ(req.get_header_value("CONTENT-LENGTH"), "12");
  EXPECT_EQ(req.get_header_value("X-TAG"), "a");
  EXPECT_EQ(req.get_header_value("Absent"), "");
  EXPECT_TRUE(req.has_param("wait"));
  EXPECT_EQ(req.get_param_value("wait"), "5");
  EXPECT_FALSE(req.has_param("Wait"));  // query names keep their case
  EXPECT_TRUE(has_request_body(req));
}

TEST(HttpMessage, ContentReplacesItsTypeAndHeadersRefuseLineBreaks) {
  Response res;
  res.set_content("a", "text/plain");
  res.set_content(std::string("{}"), "application/json");
  EXPECT_EQ(res.body, "{}");
  EXPECT_EQ(res.headers.count("content-type"), 1u);
  EXPECT_EQ(res.get_header_value("Content-Type"), "application/json");
  res.set_header("X-Bad", "a\r\nSet-Cookie: x=1");
  EXPECT_FALSE(res.has_header("X-Bad"));
  replace_header(res, "Connection", "keep-alive");
  replace_header(res, "connection", "close");
  EXPECT_EQ(res.headers.count("Connection"), 1u);
  EXPECT_EQ(res.get_header_value("Connection"), "close");
}

TEST(HttpMessage, AReaderHandsOverRawBodiesAndFormParts) {
  const ContentReader reader([](ContentReceiver receive) { return receive("abc", 3); },
                             [](FormPartHandler part, ContentReceiver receive) {
                               return part(FormPart{"mesh", "a.off", "model/x-off"}) && receive("OFF", 3);
                             });
  std::string raw, form;
  EXPECT_TRUE(reader([&](const char* data, std::size_t n) { return raw.append(data, n), true; }));
  EXPECT_EQ(raw, "abc");
  EXPECT_TRUE(reader([&](const FormPart& p) { return form += p.name + ":" + p.filename + ":" + p.content_type + ":", true; },
                     [&](const char* data, std::size_t n) { return form.append(data, n), true; }));
  EXPECT_EQ(form, "mesh:a.off:model/x-off:OFF");
}

TEST(HttpMessage, AHandlerRunsOnTheServiceTypesAlone) {
  Request req;
  req.method = "GET";
  req.path = "/";
  Response res;
  serve_web_file(req, res, "index.html");
  ASSERT_EQ(res.status, 200);
  ASSERT_TRUE(res.provider);
  EXPECT_EQ(res.content_type, "text/html; charset=utf-8");
  std::string body;
  DataSink sink{[&](const char* data, std::size_t n) { return body.append(data, n), true; }};
  ASSERT_TRUE(res.provider(0, res.content_length, sink));
  EXPECT_EQ(body.size(), res.content_length);
  EXPECT_NE(body.find("<html"), std::string::npos);

  Request again = req;
  again.headers.emplace("If-None-Match", res.get_header_value("ETag"));
  Response not_modified;
  serve_web_file(again, not_modified, "index.html");
  EXPECT_EQ(not_modified.status, 304);
  EXPECT_FALSE(not_modified.provider);
  EXPECT_THROW(serve_web_file(req, not_modified, "no-such-file.js"), HttpError);
}

}  // namespace
}  // namespace mdn::http

// The dashboard in a real browser: the small unloading pipeline runs with the
// monitor, headless Chromium opens the page, and the test reads the DOM
// through the DevTools protocol until live data shows (boxes drawn, the
// robot, the curve rising, topic rates above zero), then keeps a screenshot.
#include "pipeline_process.hpp"
#include "web_client.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <regex>

namespace plr::monitor_web::testing {
namespace {

namespace fs = std::filesystem;

// Headless Chromium with the DevTools protocol on a port it picks.
class Browser {
 public:
  Browser(const fs::path& dir, const std::string& url) {
    log_ = dir / "chromium.txt";
    const std::string profile = "--user-data-dir=" + (dir / "profile").string();
    pid_ = ::fork();
    if (pid_ == 0) {
      const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      ::dup2(fd, 2);
      ::dup2(fd, 1);
      ::execlp(CHROMIUM, CHROMIUM, "--headless=new", "--no-sandbox", "--disable-gpu",
               "--no-first-run", "--disable-extensions", "--remote-debugging-port=0",
               "--window-size=1400,1250", profile.c_str(), url.c_str(), nullptr);
      ::_exit(127);
    }
  }
  ~Browser() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      int status = 0;
      ::waitpid(pid_, &status, 0);
    }
  }

  std::string log() const {
    std::ifstream in(log_);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  }

  // The page's DevTools WebSocket, once Chromium lists it (however long it
  // takes to start on a loaded machine: ctest's timeout bounds it); null
  // when Chromium exits first.
  std::unique_ptr<WsClient> page() {
    static const std::regex listening(R"(DevTools listening on ws://127\.0\.0\.1:(\d+)/)");
    for (;;) {
      std::smatch m;
      const auto text = log();
      if (std::regex_search(text, m, listening)) {
        const auto port = static_cast<std::uint16_t>(std::stoi(m[1]));
        const auto list = nlohmann::json::parse(http_get(port, "/json/list").body, nullptr, false);
        if (list.is_array())
          for (const auto& t : list)
            if (t.value("type", "") == "page") {
              const std::string ws = t.at("webSocketDebuggerUrl");
              const auto path = ws.substr(ws.find('/', 5));
              auto client = std::make_unique<WsClient>("127.0.0.1", port, path);
              // A screenshot of a busy machine's page takes its time.
              client->set_read_timeout(std::chrono::seconds(60));
              return client;
            }
      }
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return nullptr;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }

 private:
  fs::path log_;
  pid_t pid_ = -1;
};

// One DevTools command and its result (events in between are skipped).
nlohmann::json devtools(WsClient& page, const std::string& method, nlohmann::json params) {
  static int next_id = 1;
  const int id = next_id++;
  page.send_text(nlohmann::json{{"id", id}, {"method", method}, {"params", params}}.dump());
  for (;;) {
    auto m = page.read();
    if (!m) return nullptr;
    auto j = nlohmann::json::parse(m->data, nullptr, false);
    if (j.is_object() && j.value("id", 0) == id) return j.value("result", nlohmann::json());
  }
}

// What the page shows, read from its DOM.
constexpr const char* kReadDom = R"JS(JSON.stringify({
  boxes_top: document.querySelectorAll('#top-view rect.box').length,
  boxes_side: document.querySelectorAll('#side-view rect.box').length,
  robot: document.querySelectorAll('#top-view rect.robot').length,
  curve_boxes: Number(document.getElementById('curve-line')?.dataset.boxes || 0),
  rates: [...document.querySelectorAll('#topics td.rate')].map(td => Number(td.dataset.rate)),
  nodes: [...document.querySelectorAll('#nodes td.state')].map(td => td.textContent),
  active: document.querySelectorAll('#strategy li.active').length,
  action: document.getElementById('action').textContent,
  connection: document.getElementById('connection').textContent}))JS";

TEST(Dashboard, ShowsTheLiveRunInABrowser) {
  // The small trailer unloaded again and again until the test stops the
  // run: it cannot end before the browser, however slow to start, shows it.
  const std::string world =
      (fs::path(UNLOAD_SMALL_CONFIG).parent_path() / "worlds/small_wall.yaml").string();
  PipelineProcess run(PLR_BIN, {UNLOAD_SMALL_CONFIG, "--report", "{dir}/report", "--set",
                                "pipeline=monitor_web_" + std::to_string(::getpid()), "--set",
                                "nodes.monitor={plugin: monitor_web, params: {port: 0}}", "--set",
                                "nodes.executor.params.world_file=''", "--set",
                                "nodes.executor.params.trailers=[{world_file: " + world + "}]",
                                "--set", "nodes.executor.params.cycles=0"});
  const auto port = run.monitor_port();
  ASSERT_NE(port, 0) << run.log();
  const auto page_html = http_get(port, "/");
  ASSERT_EQ(page_html.status, 200);
  EXPECT_NE(page_html.body.find("<svg id=\"top-view\""), std::string::npos);

  Browser browser(run.dir(), "http://127.0.0.1:" + std::to_string(port) + "/");
  auto page = browser.page();
  ASSERT_TRUE(page) << browser.log();

  // Read once a second until the page shows the run live; the curve rises
  // from the lowest count seen since it last fell (a new trailer restarts it).
  nlohmann::json dom;
  int rising_from = -1;
  bool live = false;
  for (int i = 0; i < 240 && !live && !run.exited(); ++i) {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    const auto r = devtools(*page, "Runtime.evaluate", {{"expression", kReadDom}});
    ASSERT_FALSE(r.is_null()) << browser.log();
    // Before the page has loaded the expression throws: no value yet.
    dom = nlohmann::json::parse(r.value("result", nlohmann::json::object()).value("value", "{}"));
    if (!dom.contains("rates")) continue;
    const int curve = dom.value("curve_boxes", 0);
    if (curve > 0 && (rising_from < 0 || curve < rising_from)) rising_from = curve;
    double max_rate = 0;
    for (double x : dom.at("rates")) max_rate = std::max(max_rate, x);
    live = dom.at("boxes_top") > 0 && dom.at("boxes_side") > 0 && dom.at("robot") > 0 &&
           rising_from > 0 && curve > rising_from && max_rate > 0 && dom.at("active") == 1;
  }
  EXPECT_TRUE(live) << dom.dump(1) << "\n" << run.log();
  EXPECT_EQ(dom.at("connection"), "live");
  EXPECT_NE(dom.at("action").get<std::string>().find('#'), std::string::npos);
  for (const auto& s : dom.at("nodes")) EXPECT_EQ(s, "active");

  const auto shot = devtools(*page, "Page.captureScreenshot", {{"format", "png"}});
  ASSERT_TRUE(shot.contains("data"));
  const fs::path out = SCREENSHOT_DIR;
  fs::create_directories(out);
  std::ofstream(out / "dashboard.png", std::ios::binary) << unbase64(shot.at("data"));
}

}  // namespace
}  // namespace plr::monitor_web::testing

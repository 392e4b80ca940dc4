// Test plug-in: a job as the run sees it. When activated it publishes its
// `figures` on `pipeline/report` and, with `done` "ok" or "failed", ends the
// job on `pipeline/done`; when deactivated it publishes `stopped_figures`
// (if given), as a node that reports what it had when it was stopped.
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

namespace {

class ReporterNode : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"figures", "stopped_figures", "done"});
    const auto& p = params().json();
    figures_ = p.value("figures", nlohmann::json::object()).dump();
    stopped_figures_ = p.contains("stopped_figures") ? p["stopped_figures"].dump() : "";
    done_ = params().get<std::string>("done", "");
    if (!done_.empty() && done_ != "ok" && done_ != "failed")
      return plr::make_error(PLR_ERR_INVALID, "param 'done': \"ok\" or \"failed\"");
    auto report = ctx().advertise<plr::msg::NodeReport>("pipeline/report");
    if (!report) return report.error();
    report_ = *report;
    auto done = ctx().advertise<plr::msg::PipelineDone>("pipeline/done");
    if (!done) return done.error();
    done_pub_ = *done;
    return {};
  }

  plr::Status on_activate() override {
    if (auto s = publish(figures_); !s) return s;
    if (done_.empty()) return {};
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(plr::msg::CreatePipelineDoneDirect(fbb, done_ == "ok", ("job " + done_).c_str()));
    return done_pub_.publish(fbb);
  }

  plr::Status on_deactivate() override {
    return stopped_figures_.empty() ? plr::Status{} : publish(stopped_figures_);
  }

 private:
  plr::Status publish(const std::string& figures) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(plr::msg::CreateNodeReportDirect(fbb, ctx().name().c_str(), figures.c_str()));
    return report_.publish(fbb);
  }

  std::string figures_, stopped_figures_, done_;
  plr::Publisher<plr::msg::NodeReport> report_;
  plr::Publisher<plr::msg::PipelineDone> done_pub_;
};

}  // namespace

PLR_PLUGIN(ReporterNode, "test_reporter", "0.1.0", PLR_KIND_OTHER,
           "Test: reports figures on pipeline/report and ends the job")
PLR_INTERFACE(plr::topic<plr::msg::NodeReport>("pipeline/report"),
              plr::topic<plr::msg::PipelineDone>("pipeline/done"))

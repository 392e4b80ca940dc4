#include "plr/chooser/model.hpp"

#include <libsvm/svm.h>
#include <plr/msg/chooser_model_generated.h>

#include <fmt/format.h>

#include <cmath>

#include "plr/sim/framed_file.hpp"
#include "plr/sim/library.hpp"

namespace plr::chooser {

namespace {

namespace msg = plr::msg;

plr::Error error(const std::string& where, const std::string& what) {
  return plr::make_error(PLR_ERR_INVALID, where + ": " + what);
}

// libsvm's dense input: indices 1..kFeatureCount, then the terminator.
using Nodes = std::array<svm_node, kFeatureCount + 1>;
void fill(Nodes& nodes, const Features& scaled) {
  for (std::size_t i = 0; i < kFeatureCount; ++i) nodes[i] = {static_cast<int>(i + 1), scaled[i]};
  nodes[kFeatureCount] = {-1, 0.0};
}

void quiet(const char*) {}

svm_parameter parameters(double c, double gamma) {
  svm_parameter p{};
  p.svm_type = C_SVC;
  p.kernel_type = RBF;
  p.gamma = gamma;
  p.C = c;
  p.cache_size = 64;
  p.eps = 1e-3;
  p.shrinking = 1;
  p.probability = 0;
  return p;
}

struct Trained {
  svm_model* model = nullptr;
  ~Trained() { svm_free_and_destroy_model(&model); }
};

}  // namespace

struct Model::Impl {
  Scaling scaling;
  std::uint32_t library_crc = 0;
  double c = 1.0, gamma = 1.0 / kFeatureCount, cv_accuracy = 0.0;
  std::uint32_t samples = 0;
  std::vector<int> labels;         // one (a single class) or two
  std::vector<int> class_support;  // support vectors per class
  std::vector<Features> vectors;   // scaled
  std::vector<double> coefficients;
  double rho = 0.0;
  std::string made_by;

  // libsvm's view of the above, pointing into it.
  std::vector<Nodes> nodes;
  std::vector<svm_node*> rows;
  double* coefficient_row = nullptr;
  svm_model view{};

  void bind() {
    nodes.resize(vectors.size());
    rows.resize(vectors.size());
    for (std::size_t i = 0; i < vectors.size(); ++i) {
      fill(nodes[i], vectors[i]);
      rows[i] = nodes[i].data();
    }
    coefficient_row = coefficients.data();
    view = svm_model{};
    view.param = parameters(c, gamma);
    view.nr_class = static_cast<int>(labels.size());
    view.l = static_cast<int>(vectors.size());
    view.SV = rows.data();
    view.sv_coef = &coefficient_row;
    view.rho = &rho;
    view.label = labels.data();
    view.nSV = class_support.data();
    view.free_sv = 0;
  }
};

Model::Model(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Model::Model(Model&&) noexcept = default;
Model& Model::operator=(Model&&) noexcept = default;
Model::~Model() = default;

plr::Expected<Model> Model::train(const std::vector<Features>& raw, const std::vector<int>& labels,
                                  const Scaling& scaling, std::uint32_t library_crc,
                                  const TrainOptions& options) {
  if (raw.size() != labels.size() || raw.empty())
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("chooser training: {} samples and {} labels (need > 0)",
                                       raw.size(), labels.size()));
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (labels[i] != kNearestLabel && labels[i] != kHardcodedLabel)
      return plr::make_error(PLR_ERR_INVALID,
                             fmt::format("chooser training: labels[{}] is {}", i, labels[i]));
  svm_set_print_string_function(&quiet);
  auto impl = std::make_unique<Impl>();
  impl->scaling = scaling;
  impl->library_crc = library_crc;
  impl->samples = static_cast<std::uint32_t>(raw.size());

  std::vector<Nodes> x(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) fill(x[i], scaling.apply(raw[i]));
  // libsvm takes non-const pointers and doubles it never writes.
  std::vector<svm_node*> rows(raw.size());
  std::vector<double> y(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) {
    rows[i] = x[i].data();
    y[i] = labels[i];
  }
  const auto train_on = [&](const std::vector<std::size_t>& subset, const svm_parameter& p) {
    std::vector<svm_node*> sx;
    std::vector<double> sy;
    for (std::size_t i : subset) {
      sx.push_back(rows[i]);
      sy.push_back(y[i]);
    }
    svm_problem problem{static_cast<int>(subset.size()), sy.data(), sx.data()};
    return Trained{svm_train(&problem, &p)};
  };

  // Folds by position (sample i in fold i mod k): deterministic, and data
  // gathered world after world spread over every fold.
  const std::size_t folds =
      std::min<std::size_t>(static_cast<std::size_t>(std::max(options.folds, 2)), raw.size());
  bool first = true;
  if (folds >= 2) {
    for (int lc : options.log2_c) {
      for (int lg : options.log2_gamma) {
        const svm_parameter p = parameters(std::ldexp(1.0, lc), std::ldexp(1.0, lg));
        std::size_t right = 0;
        for (std::size_t k = 0; k < folds; ++k) {
          std::vector<std::size_t> in, out;
          for (std::size_t i = 0; i < raw.size(); ++i) (i % folds == k ? out : in).push_back(i);
          const Trained t = train_on(in, p);
          for (std::size_t i : out)
            if (static_cast<int>(svm_predict(t.model, rows[i])) == labels[i]) ++right;
        }
        const double accuracy = static_cast<double>(right) / static_cast<double>(raw.size());
        if (first || accuracy > impl->cv_accuracy) {
          impl->c = p.C;
          impl->gamma = p.gamma;
          impl->cv_accuracy = accuracy;
          first = false;
        }
      }
    }
  }
  std::vector<std::size_t> all(raw.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  const svm_parameter p = parameters(impl->c, impl->gamma);
  svm_problem problem{static_cast<int>(raw.size()), y.data(), rows.data()};
  if (const char* bad = svm_check_parameter(&problem, &p))
    return plr::make_error(PLR_ERR_INVALID, fmt::format("chooser training: libsvm: {}", bad));
  const Trained t = train_on(all, p);
  const svm_model& m = *t.model;
  impl->labels.assign(m.label, m.label + m.nr_class);
  if (m.nr_class == 2) {
    impl->class_support.assign(m.nSV, m.nSV + 2);
    for (int i = 0; i < m.l; ++i) {
      Features v{};
      for (const svm_node* n = m.SV[i]; n->index != -1; ++n)
        v[static_cast<std::size_t>(n->index - 1)] = n->value;
      impl->vectors.push_back(v);
      impl->coefficients.push_back(m.sv_coef[0][i]);
    }
    impl->rho = m.rho[0];
  } else {
    impl->class_support.assign(1, 0);
  }
  impl->bind();
  return Model(std::move(impl));
}

Verdict Model::decide(const Features& raw) const {
  const Impl& m = *impl_;
  if (m.labels.size() < 2) return {m.labels.front() == kNearestLabel, 0.0};
  Nodes x;
  fill(x, m.scaling.apply(raw));
  double decision = 0.0;
  svm_predict_values(&m.view, x.data(), &decision);
  // libsvm's decision value is positive towards its first label.
  const double margin = m.labels[0] == kNearestLabel ? decision : -decision;
  return {margin > 0, margin};
}

double Model::accuracy(const std::vector<Features>& raw, const std::vector<int>& labels) const {
  if (raw.empty()) return 0.0;
  std::size_t right = 0;
  for (std::size_t i = 0; i < raw.size(); ++i)
    if ((decide(raw[i]).nearest ? kNearestLabel : kHardcodedLabel) == labels[i]) ++right;
  return static_cast<double>(right) / static_cast<double>(raw.size());
}

const Scaling& Model::scaling() const {
  return impl_->scaling;
}
std::uint32_t Model::library_crc() const {
  return impl_->library_crc;
}

const std::string& Model::made_by() const {
  return impl_->made_by;
}

void Model::set_made_by(std::string made_by) {
  impl_->made_by = std::move(made_by);
}
double Model::c() const {
  return impl_->c;
}
double Model::gamma() const {
  return impl_->gamma;
}
double Model::cv_accuracy() const {
  return impl_->cv_accuracy;
}
std::size_t Model::support_vectors() const {
  return impl_->vectors.size();
}

std::vector<std::uint8_t> Model::serialize() const {
  const Impl& m = *impl_;
  flatbuffers::FlatBufferBuilder fbb;
  std::vector<double> flat;
  flat.reserve(m.vectors.size() * kFeatureCount);
  for (const Features& v : m.vectors) flat.insert(flat.end(), v.begin(), v.end());
  const auto mean = fbb.CreateVector(m.scaling.mean.data(), kFeatureCount);
  const auto scale = fbb.CreateVector(m.scaling.scale.data(), kFeatureCount);
  const auto labels = fbb.CreateVector(m.labels);
  const auto support = fbb.CreateVector(m.class_support);
  const auto vectors = fbb.CreateVector(flat);
  const auto coefficients = fbb.CreateVector(m.coefficients);
  const auto made_by = fbb.CreateString(m.made_by);
  msg::FinishChooserModelBuffer(
      fbb, msg::CreateChooserModel(fbb, kModelVersion, kFeatureVersion, kFeatureCount, mean, scale,
                                   m.library_crc, m.c, m.gamma, m.cv_accuracy, m.samples, labels,
                                   support, vectors, coefficients, m.rho, made_by));
  return plr::frame(fbb.GetBufferPointer(), fbb.GetSize());
}

plr::Expected<Model> Model::deserialize(const std::uint8_t* data, std::size_t size,
                                        const std::string& origin) {
  auto framed = sim::unframe(data, size, kMaxModelBytes, "a chooser model", origin);
  if (!framed) return framed.error();
  const std::uint8_t* fb = framed->data;
  if (!msg::ChooserModelBufferHasIdentifier(fb))
    return error(origin, "byte 8: not a chooser model (identifier is not PLRM)");
  flatbuffers::Verifier verifier(fb, framed->size);
  if (!msg::VerifyChooserModelBuffer(verifier))
    return error(
        origin, fmt::format("bytes 4..{}: malformed (FlatBuffers verification)", framed->size + 4));
  const msg::ChooserModel* m = msg::GetChooserModel(fb);
  if (m->version() != kModelVersion)
    return error(origin, fmt::format("version {} is not supported (this build reads {})",
                                     m->version(), kModelVersion));
  if (m->feature_version() != kFeatureVersion || m->feature_count() != kFeatureCount)
    return error(origin, fmt::format("trained on features version {} ({} features); this build "
                                     "computes version {} ({}): train the chooser again",
                                     m->feature_version(), m->feature_count(), kFeatureVersion,
                                     kFeatureCount));
  const auto count = [](const auto* v) { return v ? static_cast<std::size_t>(v->size()) : 0u; };
  if (count(m->mean()) != kFeatureCount || count(m->scale()) != kFeatureCount)
    return error(origin, fmt::format("mean, scale: {} values each expected", kFeatureCount));
  auto impl = std::make_unique<Impl>();
  for (std::size_t i = 0; i < kFeatureCount; ++i) {
    impl->scaling.mean[i] = m->mean()->Get(static_cast<flatbuffers::uoffset_t>(i));
    impl->scaling.scale[i] = m->scale()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if (!std::isfinite(impl->scaling.mean[i]) || !(impl->scaling.scale[i] > 0) ||
        !std::isfinite(impl->scaling.scale[i]))
      return error(origin, fmt::format("scale[{}]: must be finite and > 0", i));
  }
  impl->library_crc = m->library_crc();
  impl->c = m->c();
  impl->gamma = m->gamma();
  impl->cv_accuracy = m->cv_accuracy();
  impl->samples = m->samples();
  impl->rho = m->rho();
  if (m->made_by()) impl->made_by = m->made_by()->str().substr(0, sim::kMaxMadeBy);
  if (!(impl->c > 0) || !(impl->gamma > 0) || !std::isfinite(impl->c) ||
      !std::isfinite(impl->gamma) || !std::isfinite(impl->rho))
    return error(origin, "c, gamma: must be finite and > 0, rho finite");
  const std::size_t classes = count(m->labels());
  if (classes < 1 || classes > 2 || count(m->class_support()) != classes)
    return error(origin, "labels: one or two classes, each with its support count");
  std::int64_t support = 0;  // two ints from the file: their sum must not overflow
  for (std::size_t i = 0; i < classes; ++i) {
    const int label = m->labels()->Get(static_cast<flatbuffers::uoffset_t>(i));
    const int n = m->class_support()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if ((label != kNearestLabel && label != kHardcodedLabel) || n < 0)
      return error(origin, fmt::format("labels[{}]: {} with {} support vectors", i, label, n));
    impl->labels.push_back(label);
    impl->class_support.push_back(n);
    support += n;
  }
  const auto n = static_cast<std::size_t>(support);
  if (count(m->coefficients()) != n || count(m->support_vectors()) != n * kFeatureCount)
    return error(origin, fmt::format("support_vectors: {} vectors of {} values and as many "
                                     "coefficients expected",
                                     n, kFeatureCount));
  if (classes == 2 && n == 0) return error(origin, "two classes without support vectors");
  for (std::size_t i = 0; i < n; ++i) {
    Features v;
    for (std::size_t k = 0; k < kFeatureCount; ++k) {
      v[k] = m->support_vectors()->Get(static_cast<flatbuffers::uoffset_t>(i * kFeatureCount + k));
      if (!std::isfinite(v[k]))
        return error(origin, fmt::format("support_vectors[{}]: not finite", i));
    }
    impl->vectors.push_back(v);
    const double a = m->coefficients()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if (!std::isfinite(a)) return error(origin, fmt::format("coefficients[{}]: not finite", i));
    impl->coefficients.push_back(a);
  }
  impl->bind();
  return Model(std::move(impl));
}

plr::Status Model::save(const std::filesystem::path& file) const {
  return sim::save_framed(serialize(), file);
}

plr::Expected<Model> Model::load(const std::filesystem::path& file) {
  auto bytes = sim::read_bounded_file(file, kMaxModelBytes + 8);
  if (!bytes) return bytes.error();
  return deserialize(bytes->data(), bytes->size(), file.string());
}

}  // namespace plr::chooser

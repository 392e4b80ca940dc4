#include "plugin_loader.hpp"

#include <gtest/gtest.h>

#include <dlfcn.h>
#include <unistd.h>

#include <filesystem>
#include <thread>

namespace plr::kernel {
namespace {

namespace fs = std::filesystem;

const std::string kBrokenPlugins = PLR_BROKEN_PLUGIN_DIR;
const std::string kDemoPlugins = PLR_DEMO_PLUGIN_DIR;

std::string error_of(PluginLoader& loader, const std::string& name) {
  auto library = loader.load(name);
  if (library) return "(loaded)";
  return library.error().message;
}

bool is_loaded(const std::string& path) {
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_NOLOAD);
  if (handle == nullptr) return false;
  dlclose(handle);
  return true;
}

// A private folder (mode 0700) for copies of the test plug-ins.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "plr_loader_test_XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    fs::permissions(path_, fs::perms::owner_all);
    fs::remove_all(path_);
  }
  const fs::path& path() const { return path_; }
  std::string str() const { return path_.string(); }
  // Copies a test plug-in in, mode 0755.
  std::string add(const std::string& file) const {
    const fs::path to = path_ / file;
    fs::copy_file(fs::path(kBrokenPlugins) / file, to);
    fs::permissions(to, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                            fs::perms::others_read | fs::perms::others_exec);
    return to.string();
  }

 private:
  fs::path path_;
};

TEST(PluginLoader, LoadsTheDemoPlugins) {
  PluginLoader loader({kDemoPlugins});
  auto counter = loader.load("demo_counter");
  ASSERT_TRUE(counter) << counter.error().message;
  EXPECT_EQ((*counter)->name(), "demo_counter");
  EXPECT_EQ((*counter)->path(), kDemoPlugins + "/demo_counter.so");
  EXPECT_EQ((*counter)->descriptor().abi_major, PLR_ABI_MAJOR);
  EXPECT_NE((*counter)->descriptor().node.create, nullptr);
  auto doubler = loader.load("demo_doubler");
  ASSERT_TRUE(doubler) << doubler.error().message;
  EXPECT_EQ((*doubler)->name(), "demo_doubler");
}

TEST(PluginLoader, SameNameFromSameFileIsOneLibraryUntilReleased) {
  PluginLoader loader({kBrokenPlugins});
  const std::string path = kBrokenPlugins + "/valid_plugin.so";
  auto first = loader.load("valid_plugin");
  ASSERT_TRUE(first) << first.error().message;
  auto second = loader.load("valid_plugin");
  ASSERT_TRUE(second) << second.error().message;
  EXPECT_EQ(first->get(), second->get());
  EXPECT_TRUE(is_loaded(path));

  first = Error{};
  EXPECT_TRUE(is_loaded(path)) << "unloaded while still referenced";
  second = Error{};
  EXPECT_FALSE(is_loaded(path)) << "the last reference did not unload the library";

  auto again = loader.load("valid_plugin");
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_EQ((*again)->name(), "valid_plugin");
}

TEST(PluginLoader, ConcurrentLoadsShareOneLibrary) {
  PluginLoader loader({kBrokenPlugins, kDemoPlugins});
  auto held = loader.load("valid_plugin");
  ASSERT_TRUE(held) << held.error().message;
  std::vector<std::string> failures[2];
  std::vector<std::thread> threads;
  for (auto& failed : failures) {
    threads.emplace_back([&loader, &held, &failed] {
      for (int i = 0; i < 200; ++i) {
        auto library = loader.load(i % 2 == 0 ? "valid_plugin" : "demo_counter");
        if (!library)
          failed.push_back(library.error().message);
        else if (i % 2 == 0 && library->get() != held->get())
          failed.push_back("a second copy of valid_plugin");
      }
    });
  }
  for (auto& t : threads) t.join();
  for (const auto& failed : failures)
    EXPECT_TRUE(failed.empty()) << failed.size() << " failures, first: " << failed.front();
}

TEST(PluginLoader, MissingFileListsSearchPaths) {
  PluginLoader loader({kBrokenPlugins, "/nonexistent/plugins"});
  EXPECT_EQ(error_of(loader, "nothing_here"),
            "nothing_here.so: not found in the plug-in search paths: " + kBrokenPlugins +
                ", /nonexistent/plugins");
  PluginLoader empty({});
  EXPECT_EQ(error_of(empty, "x"), "x.so: not found in the plug-in search paths: (none configured)");
}

TEST(PluginLoader, RefusesNamesThatLeaveTheSearchPaths) {
  PluginLoader loader({kBrokenPlugins});
  const std::string cause =
      ": refused: a plug-in name must not contain '/' or '..', which would load from outside "
      "the search paths (" +
      kBrokenPlugins + ")";
  EXPECT_EQ(error_of(loader, "../test_plugins/valid_plugin"),
            "../test_plugins/valid_plugin.so" + cause);
  EXPECT_EQ(error_of(loader, kBrokenPlugins + "/valid_plugin"),
            kBrokenPlugins + "/valid_plugin.so" + cause);
  EXPECT_EQ(error_of(loader, "a..b"), "a..b.so" + cause);
  EXPECT_EQ(error_of(loader, ""), ".so: refused: empty plug-in name");
}

TEST(PluginLoader, RefusesOldAbi) {
  PluginLoader loader({kBrokenPlugins});
  EXPECT_EQ(error_of(loader, "old_abi"),
            kBrokenPlugins +
                "/old_abi.so: refused: wrong plug-in ABI major: found 0, expected 1 (rebuild the "
                "plug-in against this SDK)");
}

TEST(PluginLoader, RefusesMissingEntryPoint) {
  PluginLoader loader({kBrokenPlugins});
  EXPECT_EQ(error_of(loader, "no_entry"),
            kBrokenPlugins +
                "/no_entry.so: refused: no entry point 'plr_plugin_entry' (not a PLR plug-in, or "
                "built without PLR_PLUGIN)");
}

TEST(PluginLoader, RefusesDescriptorNameDifferentFromFile) {
  PluginLoader loader({kBrokenPlugins});
  EXPECT_EQ(error_of(loader, "misnamed"),
            kBrokenPlugins +
                "/misnamed.so: refused: the descriptor names the plug-in 'another_name', but the "
                "file is misnamed.so (they must match)");
}

TEST(PluginLoader, ReportsDlopenFailure) {
  PluginLoader loader({kBrokenPlugins});
  const std::string message = error_of(loader, "unresolved");
  EXPECT_EQ(message.rfind(kBrokenPlugins + "/unresolved.so: refused: dlopen failed: ", 0), 0u)
      << message;
  EXPECT_NE(message.find("undefined symbol: plr_test_symbol_nobody_defines"), std::string::npos)
      << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
}

TEST(PluginLoader, RefusesGroupOrWorldWritableFile) {
  TempDir dir;
  const std::string file = dir.add("valid_plugin.so");
  PluginLoader loader({dir.str()});
  fs::permissions(file, fs::perms::group_write, fs::perm_options::add);
  EXPECT_EQ(error_of(loader, "valid_plugin"),
            file + ": refused: file " + file + " is group- or world-writable (mode 0775)");
  fs::permissions(file, fs::perms::group_write, fs::perm_options::remove);
  fs::permissions(file, fs::perms::others_write, fs::perm_options::add);
  EXPECT_EQ(error_of(loader, "valid_plugin"),
            file + ": refused: file " + file + " is group- or world-writable (mode 0757)");
  fs::permissions(file, fs::perms::others_write, fs::perm_options::remove);
  EXPECT_EQ(error_of(loader, "valid_plugin"), "(loaded)");
}

TEST(PluginLoader, RefusesGroupOrWorldWritableFolder) {
  TempDir dir;
  const std::string file = dir.add("valid_plugin.so");
  PluginLoader loader({dir.str()});
  fs::permissions(dir.path(), fs::perms::all);
  EXPECT_EQ(error_of(loader, "valid_plugin"),
            file + ": refused: folder " + dir.str() + " is group- or world-writable (mode 0777)");
}

// A safe folder inside one anybody may write to: whoever can write the outer
// one can rename the inner one and put their own in its place.
TEST(PluginLoader, RefusesAFolderInsideAWritableOneUpToTheRoot) {
  TempDir dir;
  const fs::path inner = dir.path() / "inner";
  fs::create_directory(inner);
  fs::permissions(inner, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                             fs::perms::others_read | fs::perms::others_exec);
  fs::copy_file(fs::path(kBrokenPlugins) / "valid_plugin.so", inner / "valid_plugin.so");
  PluginLoader loader({inner.string()});
  fs::permissions(dir.path(), fs::perms::all);
  const std::string file = (inner / "valid_plugin.so").string();
  EXPECT_EQ(error_of(loader, "valid_plugin"),
            file + ": refused: folder " + dir.str() + " is group- or world-writable (mode 0777)");
  fs::permissions(dir.path(), fs::perms::sticky_bit, fs::perm_options::add);
  EXPECT_EQ(error_of(loader, "valid_plugin"), "(loaded)") << "a sticky folder, as /tmp";
}

// Its owner can replace anything in it, whatever the mode says.
TEST(PluginLoader, RefusesAFolderOwnedByAnotherUser) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root to give a folder to another user";
  TempDir dir;
  const std::string file = dir.add("valid_plugin.so");
  fs::permissions(dir.path(), fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                  fs::perms::others_read | fs::perms::others_exec);
  ASSERT_EQ(chown(dir.path().c_str(), 65534, 65534), 0);
  PluginLoader loader({dir.str()});
  EXPECT_EQ(error_of(loader, "valid_plugin"),
            file + ": refused: folder " + dir.str() +
                " is owned by uid 65534 (only root or uid 0 may own it)");
  ASSERT_EQ(chown(file.c_str(), 65534, 65534), 0);
  ASSERT_EQ(chown(dir.path().c_str(), 0, 0), 0);
  EXPECT_EQ(
      error_of(loader, "valid_plugin"),
      file + ": refused: file " + file + " is owned by uid 65534 (only root or uid 0 may own it)");
}

TEST(PluginLoader, RefusesSameNameFromAnotherFile) {
  TempDir first_path;
  TempDir second_path;
  const std::string original = second_path.add("valid_plugin.so");
  PluginLoader loader({first_path.str(), second_path.str()});
  auto loaded = loader.load("valid_plugin");
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ((*loaded)->path(), original);

  // A copy appears earlier in the search order while the first one is in use.
  const std::string copy = first_path.add("valid_plugin.so");
  EXPECT_EQ(error_of(loader, "valid_plugin"),
            copy + ": refused: duplicate: plug-in 'valid_plugin' is already loaded from " +
                fs::canonical(original).string());

  // Once the first is unloaded, nothing conflicts.
  loaded = Error{};
  auto reloaded = loader.load("valid_plugin");
  ASSERT_TRUE(reloaded) << reloaded.error().message;
  EXPECT_EQ((*reloaded)->path(), copy);
}

TEST(PluginLoader, ListDescribesLoadablePluginsAndReportsBrokenOnes) {
  TempDir shadow;
  shadow.add("valid_plugin.so");
  PluginLoader loader({kBrokenPlugins, shadow.str(), "/nonexistent/plugins"});
  std::vector<std::string> errors;
  const std::vector<PluginInfo> plugins = loader.list(&errors);

  ASSERT_EQ(plugins.size(), 1u);
  const PluginInfo& info = plugins[0];
  EXPECT_EQ(info.name, "valid_plugin");
  EXPECT_EQ(info.version, "0.1.0");
  EXPECT_EQ(info.kind, "other");
  EXPECT_EQ(info.description, "a loader test plug-in");
  EXPECT_EQ(info.path, kBrokenPlugins + "/valid_plugin.so");
  EXPECT_EQ(info.abi_major, PLR_ABI_MAJOR);
  EXPECT_EQ(info.abi_minor, PLR_ABI_MINOR);

  ASSERT_EQ(errors.size(), 6u);
  const std::vector<std::string> prefixes = {
      kBrokenPlugins + "/misnamed.so: refused: the descriptor names",
      kBrokenPlugins + "/no_entry.so: refused: no entry point",
      kBrokenPlugins + "/old_abi.so: refused: wrong plug-in ABI major",
      kBrokenPlugins + "/unresolved.so: refused: dlopen failed",
      shadow.str() +
          "/valid_plugin.so: ignored: shadowed by valid_plugin.so in an earlier search "
          "path",
      "/nonexistent/plugins: cannot list plug-ins: No such file or directory"};
  for (std::size_t i = 0; i < prefixes.size(); ++i)
    EXPECT_EQ(errors[i].rfind(prefixes[i], 0), 0u) << errors[i];

  // The temporary handles are gone again.
  EXPECT_FALSE(is_loaded(kBrokenPlugins + "/valid_plugin.so"));
}

TEST(PluginLoader, DefaultPathIsNextToTheBinary) {
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const std::string path = default_plugin_path();
  EXPECT_EQ(path, fs::weakly_canonical(exe.parent_path() / ".." / "lib" / "plugins").string());
  EXPECT_EQ(path.find(".."), std::string::npos);
  EXPECT_TRUE(fs::path(path).is_absolute());
}

}  // namespace
}  // namespace plr::kernel

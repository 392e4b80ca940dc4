/* One source for the loader's test plug-ins; each build sets what is wrong
 * with it (see frontend_tests.cmake). Plain C, like a plug-in written against
 * the ABI header alone:
 *   TEST_PLUGIN_NAME         the name in the descriptor
 *   TEST_PLUGIN_ABI_MAJOR    defaults to PLR_ABI_MAJOR; 0 stands for a plug-in
 *                            built against an old SDK
 *   TEST_PLUGIN_NO_ENTRY     exports no entry point
 *   TEST_PLUGIN_UNRESOLVED   needs a symbol nothing provides, so dlopen fails
 *   TEST_PLUGIN_KIND         defaults to PLR_KIND_OTHER
 */
#include <plr/plugin_abi.h>

#ifndef TEST_PLUGIN_ABI_MAJOR
#define TEST_PLUGIN_ABI_MAJOR PLR_ABI_MAJOR
#endif

#ifndef TEST_PLUGIN_KIND
#define TEST_PLUGIN_KIND PLR_KIND_OTHER
#endif

#define EXPORT __attribute__((visibility("default")))

static void* create(const plr_host_api* host) {
  return (void*)host;
}
static void destroy(void* node) {
  (void)node;
}
static plr_status step(void* node, char* err, size_t err_size) {
  (void)node, (void)err, (void)err_size;
  return PLR_OK;
}

#ifdef TEST_PLUGIN_UNRESOLVED
extern int plr_test_symbol_nobody_defines(void);
EXPORT int plr_test_use_missing(void) {
  return plr_test_symbol_nobody_defines();
}
#endif

#ifdef TEST_PLUGIN_NO_ENTRY
EXPORT const plr_plugin_descriptor* plr_plugin_entry_misspelt(void);
#define ENTRY plr_plugin_entry_misspelt
#else
EXPORT const plr_plugin_descriptor* plr_plugin_entry(void);
#define ENTRY plr_plugin_entry
#endif

const plr_plugin_descriptor* ENTRY(void) {
  static const plr_plugin_descriptor descriptor = {TEST_PLUGIN_ABI_MAJOR,
                                                   PLR_ABI_MINOR,
                                                   TEST_PLUGIN_NAME,
                                                   "0.1.0",
                                                   "a loader test plug-in",
                                                   TEST_PLUGIN_KIND,
                                                   {create, destroy, step, step, step, step}};
  return &descriptor;
}

// Linked into every target of a ThreadSanitizer build (PLR_TSAN). Debian's
// Cyclone DDS (and its security plug-ins) is not instrumented: it hands
// buffers, mutexes and samples between its threads with atomics TSan cannot
// see, so its own memory looks raced. Reports with a frame in those
// libraries are dropped. The price: a race between our code running on a
// DDS thread (the bridge's listeners) and another thread is dropped too;
// every other thread of ours stays checked.
// Visible by default: targets build with hidden visibility, and the runtime
// finds this hook only through the dynamic symbol table.
extern "C" __attribute__((visibility("default"))) const char* __tsan_default_suppressions() {
  return "race:libddsc.so\n"
         "race:libdds_security\n";
}

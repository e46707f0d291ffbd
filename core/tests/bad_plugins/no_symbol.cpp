// A shared object that is not an fba plugin.
extern "C" [[gnu::visibility("default")]] int not_an_fba_plugin() { return 42; }

// A shared library that loads but is no graspbed plugin (no graspbed_controller_plugin symbol).
extern "C" __attribute__((visibility("default"))) int some_other_library_function() { return 42; }

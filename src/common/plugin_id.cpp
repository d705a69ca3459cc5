// Every plugin's identity (common/plugin.hpp): the version and plugin headers it was built
// with, which the loader compares with the program's own before it uses the plugin's tables.
extern "C" __attribute__((visibility("default"))) const char* trochomill_plugin_id() {
  return TROCHOMILL_PLUGIN_ID;
}

#include "cli/dds_options.hpp"

#include "jpcr/io/params.hpp"

namespace jpcr::cli {

void add_dds_options(Arguments& args) {
  args.option("params", "parameter YAML whose dds: section sets domain, topics and QoS")
      .option("domain", "DDS domain id 0..232 (overrides dds.domain_id)")
      .option("cyclone-uri",
              "Cyclone DDS configuration, file://PATH or XML (overrides dds.cyclone_uri and "
              "$CYCLONEDDS_URI; configs/cyclonedds_loopback.xml keeps traffic on this machine)");
}

DdsConfig dds_config_from(const Arguments& args) {
  DdsConfig config = args.has("params") ? load_params(args.get("params")).dds : DdsConfig{};
  if (args.has("domain")) {
    config.domain_id = args.get_int("domain");
    if (config.domain_id < 0 || config.domain_id > 232) {
      throw UsageError("--domain must be in 0..232, got " + args.get("domain"));
    }
  }
  if (args.has("cyclone-uri")) config.cyclone_uri = args.get("cyclone-uri");
  return config;
}

}  // namespace jpcr::cli

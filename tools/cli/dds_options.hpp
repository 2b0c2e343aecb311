// The DDS options the jpcr DDS programs share: --params FILE (its dds: section), --domain N and
// --cyclone-uri URI.
#pragma once

#include "cli/arguments.hpp"
#include "jpcr/io/dds/dds_config.hpp"

namespace jpcr::cli {

/// Declares --params, --domain and --cyclone-uri on `args`.
void add_dds_options(Arguments& args);

/// The dds: section of --params (defaults without it), with --domain and --cyclone-uri applied.
/// The Cyclone configuration comes from --cyclone-uri, dds.cyclone_uri, else $CYCLONEDDS_URI.
DdsConfig dds_config_from(const Arguments& args);

}  // namespace jpcr::cli

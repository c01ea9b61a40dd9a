// `fploc launch --check`: the files a graph's options name must exist and parse before anything starts —
// floor plans and maps (every PlanSource.file: .dxf/.csv/.json/.fpmap through the floorplan reader), OS-1
// metadata (`metadata` fields, unless another node of the graph writes that file at run time via
// `metadata_out`, or the driver fetches it from `sensor_hostname`), pcap captures (`pcap`: the magic
// number) and the dashboard's `graph`. Files nodes write (`*_out`, `out_*`, the pose logger's files, `stats_file`): their
// folder must exist (docs/notes/launch-check.md).
#pragma once
#include <vector>

#include "fploc/runtime/graph.h"

namespace fploc::launch {

// Appends one error per bad file (file:line of the option, the resolved path and the reader's message).
// skip_remote: leave out the nodes that run on another host (a launch: their files are on that host).
void check_option_files(const fploc::rt::LoadedGraph& g, std::vector<fploc::rt::GraphError>& errors,
                        bool skip_remote = false);

// Runs the option checks each enabled node does at start (fploc::config::check_options: the options mapped
// to the node's Configs) and appends one error per node that would refuse its options: file:line of the
// option (of the options block when the value came from --set), "node 'NAME': BLOCK.FIELD: why".
void check_option_values(const fploc::rt::LoadedGraph& g, std::vector<fploc::rt::GraphError>& errors);

}  // namespace fploc::launch

// bricklayer-planner: collapse previews and next-block hints as a process on the bus (PlannerNode).
#include "bricklayer/planner/planner_node.h"
#include "bricklayer/runtime/node_main.h"

int main(int argc, char** argv) { return bricklayer::runtime::node_main<bricklayer::planner::PlannerNode>(argc, argv); }

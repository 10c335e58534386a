// bricklayer-logger: the bus recorder as a process (LoggerNode).
#include "bricklayer/logger/logger_node.h"
#include "bricklayer/runtime/node_main.h"

int main(int argc, char** argv) { return bricklayer::runtime::node_main<bricklayer::logger::LoggerNode>(argc, argv); }

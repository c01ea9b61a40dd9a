// The main of every node executable: the node class linked beside it registered itself.
#include "fploc/runtime/node.h"

int main(int argc, char** argv) { return fploc::rt::node_main(argc, argv); }

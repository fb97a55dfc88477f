// concert: the command-line front end of the CONCERT stack (`concert help` lists the verbs).
#include <iostream>

#include "verbs.hpp"

int main(int argc, char** argv) {
  concert::cli::Cli concert("concert", "The CONCERT stack's command line.", std::cout, std::cerr);
  concert::tool::register_all(concert);
  return concert.run(argc, argv);
}

// The members of an option group (base/options.h), included inside its struct after
//   #define MS_OPTION_LIST "folder/foo_options_def.h"
// the list of its MS_OPTION lines: the fields with their defaults, and ForEachOption, which hands
// every field and its OptionSpec to a visitor, in declaration order. No include guard: every
// group includes it once.

#define MS_OPTION MS_OPTION_FIELD
#include MS_OPTION_LIST
#undef MS_OPTION

template <typename Self, typename Visitor>
static void ForEachOption(Self&& self, Visitor&& visit) {
#define MS_OPTION MS_OPTION_VISIT
#include MS_OPTION_LIST
#undef MS_OPTION
}

#undef MS_OPTION_LIST

// The map layer's colours: one per cell class, and the page around a map picture.
#include <gseg/map/map_colours.hpp>

#include <gseg/palette.hpp>

namespace gseg::map {

Rgb colourOf(ColumnClass c) {
    switch (c) {
        case ColumnClass::Traversable: return {gseg::palette::kGround[0], gseg::palette::kGround[1], gseg::palette::kGround[2]};
        case ColumnClass::Obstacle: return {gseg::palette::kNonGround[0], gseg::palette::kNonGround[1], gseg::palette::kNonGround[2]};
        default: return {105, 105, 115};
    }
}

Rgb backgroundColour() { return {24, 24, 30}; }

}  // namespace gseg::map

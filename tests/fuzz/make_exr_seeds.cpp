// Writes small EXR seeds of several layouts (compressions, half RGBA, tiled float Y with
// an offset data window) into a directory: the generated part of tests/fuzz/corpus/exr.
//   g++ -std=c++17 make_exr_seeds.cpp -I/usr/include/OpenEXR -I/usr/include/Imath -lOpenEXR -lImath -o seeds
//   ./seeds tests/fuzz/corpus/exr
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfTiledOutputFile.h>
#include <string>
#include <vector>
int main(int, char** argv) {
  std::string dir = argv[1];
  const int w = 7, h = 5;
  std::vector<Imf::Rgba> px(w * h);
  for (int i = 0; i < w * h; ++i) px[i] = Imf::Rgba(i * 0.1f, 1.f - i * 0.02f, 0.5f, 1.f);
  struct C {
    Imf::Compression c;
    const char* n;
  } cs[] = {{Imf::NO_COMPRESSION, "rgba_half_none"},     {Imf::RLE_COMPRESSION, "rgba_half_rle"},
            {Imf::PIZ_COMPRESSION, "rgba_half_piz"},     {Imf::ZIPS_COMPRESSION, "rgba_half_zips"},
            {Imf::PXR24_COMPRESSION, "rgba_half_pxr24"}, {Imf::B44_COMPRESSION, "rgba_half_b44"},
            {Imf::DWAA_COMPRESSION, "rgba_half_dwaa"}};
  for (auto& c : cs) {
    Imf::RgbaOutputFile f((dir + "/" + c.n + ".exr").c_str(), w, h, Imf::WRITE_RGBA, 1, Imath::V2f(0, 0), 1,
                          Imf::INCREASING_Y, c.c);
    f.setFrameBuffer(px.data(), 1, w);
    f.writePixels(h);
  }
  {  // float Y, tiled, offset data window
    Imath::Box2i dw(Imath::V2i(3, -2), Imath::V2i(3 + w - 1, -2 + h - 1));
    Imf::Header hd(Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(w, h)), dw);
    hd.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    hd.setTileDescription(Imf::TileDescription(4, 4, Imf::ONE_LEVEL));
    std::vector<float> y(w * h, 0.25f);
    Imf::TiledOutputFile f((dir + "/y_float_tiled_offset.exr").c_str(), hd);
    Imf::FrameBuffer fb;
    fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, y.data(), dw));
    f.setFrameBuffer(fb);
    f.writeTiles(0, f.numXTiles() - 1, 0, f.numYTiles() - 1);
  }
  return 0;
}
